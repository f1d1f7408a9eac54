"""Workers that meet at barriers: one launch per CPU thread, each taking its share of every pass
of a loop of short dependent passes (the implicit solver's sweeps, one pass per colour), meeting
the others between passes at a spin on an atomic counter (some microseconds, against some 110 us
for handing a launch to another thread)."""

from __future__ import annotations

from typing import Any

import warp as wp


def _sched_yield_address() -> int:
    """Where the C library's ``sched_yield`` is (POSIX), for workers to call; 0 where there is
    none (the workers then only spin)."""
    try:
        import ctypes

        return int(ctypes.cast(ctypes.CDLL(None).sched_yield, ctypes.c_void_p).value or 0)
    except (OSError, AttributeError, TypeError):
        return 0


SCHED_YIELD = _sched_yield_address()
"""The address of the C library's ``sched_yield`` (0 where there is none)."""


@wp.struct
class WorkerSync:
    """What the workers of a :meth:`~party.launch.Launcher.launch_workers` launch share:
    ``counters`` (arrivals, generation and failed, left zeroed by a launch, and a running count
    of the times a waiting worker gave its core away), the spins a worker waits before it gives
    up on the others, the spins before it starts giving its core away
    (:class:`~party.launch.LaunchSettings`) and the address of ``sched_yield`` (0: spin only)."""

    counters: wp.array(dtype=int)
    max_spins: int
    yield_after: int
    yield_cpu: wp.uint64


def worker_sync(device: Any = None) -> WorkerSync:
    """A :class:`WorkerSync` with zeroed counters on ``device``, for a workers' launch (which
    sets its spin limits at each launch)."""
    sync = WorkerSync()
    sync.counters = wp.zeros(4, dtype=int, device=device)
    sync.yield_cpu = SCHED_YIELD
    return sync


@wp.func_native("""
#if !defined(__CUDA_ARCH__)
typedef wp::int32 (*yield_function)();
int* counter = (int*)sync.counters.data;
unsigned long long yield_address = (unsigned long long)sync.yield_cpu;
int generation = __atomic_load_n(counter + 1, __ATOMIC_ACQUIRE);
if (__atomic_add_fetch(counter, 1, __ATOMIC_ACQ_REL) == workers) {
    __atomic_store_n(counter, 0, __ATOMIC_RELAXED);
    __atomic_store_n(counter + 1, generation + 1, __ATOMIC_RELEASE);
} else {
    long long spins = 0;
    while (__atomic_load_n(counter + 1, __ATOMIC_ACQUIRE) == generation) {
        if (__atomic_load_n(counter + 2, __ATOMIC_RELAXED) != 0 || ++spins > sync.max_spins) {
            __atomic_store_n(counter + 2, 1, __ATOMIC_RELAXED);
            break;
        }
        if (spins > sync.yield_after && yield_address != 0) {
            ((yield_function)yield_address)();
            __atomic_add_fetch(counter + 3, 1, __ATOMIC_RELAXED);
            continue;
        }
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
    }
}
#endif
""")
def worker_barrier(sync: WorkerSync, workers: int):
    """Wait until all ``workers`` of a workers' launch have arrived here; what each wrote before
    is then visible to all. A worker that has waited ``sync.yield_after`` spins gives its core
    away at every further spin. On CUDA a launch has one worker, and this does nothing."""
    ...
