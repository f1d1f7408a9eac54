"""Launching kernels: replayed where a call repeats, and item-wise kernels on every CPU core.

Packing a kernel's arguments costs ``wp.launch`` some 40 us on the CPU, more than many of
our kernels take to run (a plastic-limit sweep over a garment's 6,000 elements: 35 us), and
a step of a garment drape makes about a hundred launches. :func:`launch` therefore keeps the
packed arguments of each distinct call (Warp's recorded launch, ``record_cmd=True``) and
replays them when the same kernel is launched again over the same dimensions with the same
arrays and values: about 6 us in all.

Warp runs a CPU launch's threads one after another on one core. A kernel whose thread
``first + wp.tid()`` writes only its own item's outputs (and at most sets flags to a constant)
gives the same result whichever order its items run in, so :func:`launch_items` cuts its range
into one chunk per core and launches the chunks from a pool of Python threads at once: Warp
releases the interpreter lock while a CPU kernel runs. Handing a chunk to another thread and
waiting for it costs some 110 us on this kind of machine (a kernel of 130 us on one thread took
180 on two, one of 1 ms 0.6 ms), so a kernel is split only where one thread would take longer
than :data:`SPLIT_SECONDS`, judged from its own earlier launches' time per item. On CUDA, and
while a graph is being captured (a CPU graph replays its launches in order on one thread), it
is one plain launch.

Warp's CPU atomics are plain read-modify-writes, so a kernel launched this way must not
accumulate into shared memory; a counter it bumps (``wp.atomic_add``) may lose increments
between chunks, though it stays non-zero when any was made. ``$PARTY_THREADS`` sets the number
of threads (default: the cores this process may use).

A loop of many short dependent launches (the implicit solver's sweeps: one launch per colour of
nodes, some tens of microseconds each) gains nothing from a thread handoff per launch. There
:func:`launch_workers` starts one launch per thread, once, each worker taking its share of every
pass and meeting the others at :func:`worker_barrier` between passes (a spin on an atomic
counter: some microseconds, against 110 us for a handoff).
"""

from __future__ import annotations

import os
import time
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Sequence

import warp as wp

from .errors import WorkersLost

WORKER_SPINS = (1 << 31) - 1
"""Spins at a :func:`worker_barrier` before a worker gives up on the others (a quarter of an hour,
yielding at every spin past :data:`YIELD_AFTER_SPINS`): a worker that never arrives is a bug,
which this turns into an error rather than a hang."""

MIN_CHUNK = 1024
"""Fewest items worth a thread of their own."""

SPLIT_SECONDS = 4.0e-4
"""Shortest time on one thread [s] for which a launch is split over threads: the split saves
half of it and costs some 110 us."""
_item_seconds: dict[Any, float] = {}

_CORES = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
_pool: ThreadPoolExecutor | None = None
_pool_threads = 0
_loaded: set[tuple[str, str]] = set()

MAX_RECORDED = 512
"""Recorded launches kept (the least recently used go first). A recorded launch holds on to its
arrays, so this bounds the memory that models no longer in use can keep; a garment drape's
steps make about a hundred distinct calls."""
_recorded: OrderedDict[tuple, Any] = OrderedDict()
_SCALARS = (bool, int, float)


def launch(kernel: Any, dim: int | tuple[int, ...], inputs: Sequence[Any], outputs: Sequence[Any] = (),
           device: Any = None) -> None:
    """``wp.launch(kernel, dim, inputs, outputs, device)``, replayed from a recorded launch when
    the same call was made before: the same kernel and dimensions, the same array objects
    (other array kinds: the same address, shape and strides), the same scalar values and
    structs with the same fields. Calls with other arguments, and any while a graph is being
    captured, are plain launches."""
    device = wp.get_device(device)
    key = None if device.is_capturing else _call_key(kernel, dim, inputs, outputs, device)
    if key is None:
        wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device)
    else:
        _recorded_launch(key, kernel, dim, inputs, outputs, device).launch()


def _recorded_launch(key: tuple | None, kernel: Any, dim: Any, inputs: Sequence[Any], outputs: Sequence[Any],
                     device: Any) -> Any:
    """The recorded launch kept for the call ``key`` (:func:`_call_key`), recorded now if none
    was; one with ``key`` None is recorded and not kept."""
    command = _recorded.get(key) if key is not None else None
    if command is None:
        command = wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device, record_cmd=True)
        if key is not None:
            _recorded[key] = command
            if len(_recorded) > MAX_RECORDED:
                _recorded.popitem(last=False)
    else:
        _recorded.move_to_end(key)
    return command


def _call_key(kernel: Any, dim: Any, inputs: Sequence[Any], outputs: Sequence[Any], device: Any) -> tuple | None:
    """What identifies a call's packed arguments; None where an argument is of a kind not
    covered (it is then launched plainly)."""
    parts: list[Any] = [kernel, dim, device.alias]
    for arg in (*inputs, *outputs):
        if type(arg) is wp.array:
            parts.append(id(arg))  # the record holds on to the array, so no other object can take its id
            continue
        part = _value_key(arg)
        if part is None:
            return None
        parts.append(part)
    return tuple(parts)


def _value_key(arg: Any) -> tuple | None:
    """What a recorded launch packs of an argument: an array's address, shape and strides, a
    scalar's, vector's or matrix's value, a struct's fields (so a struct whose fields were
    changed is recorded anew); None for other kinds."""
    kind = type(arg)
    if kind in _SCALARS:
        return (kind, arg)
    if isinstance(arg, wp.array):
        return (arg.ptr, arg.shape, arg.strides)
    if hasattr(arg, "_length_"):  # Warp's vector and matrix values
        return (kind, tuple(arg))
    fields = getattr(getattr(arg, "_cls", None), "vars", None)  # a Warp struct
    if fields is None:
        return None
    parts = [kind]
    for name in fields:
        value = getattr(arg, name)
        part = ("unset",) if value is None else _value_key(value)
        if part is None:
            return None
        parts.append(part)
    return tuple(parts)


YIELD_AFTER_SPINS = 1000
"""Spins at a :func:`worker_barrier` (each a pause of some 10-40 ns) after which a waiting worker
gives its core away (``sched_yield``) at every further spin. Most meetings of balanced passes
take microseconds; a worker that waits much longer may be waiting for one that has no core:
another process took one, and a spinning worker would hold the core its partner needs until
the scheduler's time slice ends. (Where no other thread wants the core, the call returns at
once: some 0.4 us.) Without yielding, a 64 x 64 sheet's self-colliding implicit
steps took 41.8 ms instead of 7.7 beside one busy process on a 2-core machine (its sweeps 34.4
ms instead of 3.0), against 12.2 ms on one thread."""


def _sched_yield_address() -> int:
    """Where the C library's ``sched_yield`` is (POSIX), for workers to call; 0 where there is
    none (the workers then only spin)."""
    try:
        import ctypes

        return int(ctypes.cast(ctypes.CDLL(None).sched_yield, ctypes.c_void_p).value or 0)
    except (OSError, AttributeError, TypeError):
        return 0


_SCHED_YIELD = _sched_yield_address()


@wp.struct
class WorkerSync:
    """What the workers of a :func:`launch_workers` launch share: ``counters`` (arrivals,
    generation and failed, left zeroed by a launch, and a running count of the times a waiting
    worker gave its core away), the spins a worker waits before it gives up on the others
    (:data:`WORKER_SPINS`), the spins before it starts giving its core away
    (:data:`YIELD_AFTER_SPINS`) and the address of ``sched_yield`` (0: spin only)."""

    counters: wp.array(dtype=int)
    max_spins: int
    yield_after: int
    yield_cpu: wp.uint64


def worker_sync(device: Any = None) -> WorkerSync:
    """A :class:`WorkerSync` with zeroed counters on ``device``, for :func:`launch_workers`
    (which sets its spin limits at each launch)."""
    sync = WorkerSync()
    sync.counters = wp.zeros(4, dtype=int, device=device)
    sync.yield_cpu = _SCHED_YIELD
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
    """Wait until all ``workers`` of a :func:`launch_workers` launch have arrived here; what each
    wrote before is then visible to all. A worker that has waited :data:`YIELD_AFTER_SPINS`
    spins gives its core away at every further spin. On CUDA a launch has one worker, and this
    does nothing."""
    ...


def thread_count() -> int:
    """Threads :func:`launch_items` uses on the CPU: ``$PARTY_THREADS`` (a whole number from 1),
    else the cores this process may use."""
    given = os.environ.get("PARTY_THREADS")
    if given is None or given.strip() == "":
        return max(_CORES, 1)
    try:
        threads = int(given)
    except ValueError:
        threads = 0
    if threads < 1:
        from .errors import InvalidInput

        raise InvalidInput(f"PARTY_THREADS must be a whole number of threads from 1, got {given!r}")
    return threads


def launch_items(kernel: Any, first: int, count: int, inputs: Sequence[Any], device: Any) -> None:
    """Launch ``kernel`` over items ``first`` .. ``first + count - 1``; the kernel's first
    argument is the item of thread 0 (its item is ``first + wp.tid()``), ``inputs`` the rest.
    See the module docstring for what such a kernel may write."""
    if count <= 0:
        return
    device = wp.get_device(device)
    threads = min(thread_count(), count // MIN_CHUNK)
    key = (kernel.key, str(device))
    if device.is_cuda or device.is_capturing:
        launch(kernel, count, [first, *inputs], device=device)
        return
    if threads < 2 or key not in _loaded:
        launch(kernel, count, [first, *inputs], device=device)
        _loaded.add(key)  # the first launch compiles and loads the module, which threads must not race on
        return
    per_item = _item_seconds.get(key)
    if per_item is None or per_item * count < SPLIT_SECONDS:
        started = time.perf_counter()
        launch(kernel, count, [first, *inputs], device=device)
        seconds = (time.perf_counter() - started) / count
        _item_seconds[key] = seconds if per_item is None else 0.9 * per_item + 0.1 * seconds
        return
    pool = _thread_pool(threads - 1)
    bounds = [first + count * k // threads for k in range(threads + 1)]
    others = [pool.submit(launch, kernel, bounds[k + 1] - bounds[k], [bounds[k], *inputs], device=device)
              for k in range(1, threads)]
    launch(kernel, bounds[1] - bounds[0], [bounds[0], *inputs], device=device)
    for other in others:
        other.result()


def worker_count(items: int, device: Any = None) -> int:
    """Workers :func:`launch_workers` should use for ``items`` items per pass: up to
    :func:`thread_count` on the CPU, but no more than the cores this process may use (a worker
    spinning at a barrier holds its core, so one waiting for a core would stall the others for
    the scheduler's time slice), at least :data:`MIN_CHUNK` items each; 1 on CUDA."""
    if wp.get_device(device).is_cuda:
        return 1
    return max(1, min(thread_count(), _CORES, items // MIN_CHUNK))


def launch_workers(kernel: Any, workers: int, sync: WorkerSync, inputs: Sequence[Any], device: Any = None) -> None:
    """Launch ``kernel`` once per worker (``dim=1``), each on its own CPU thread at once (for the
    CPU: see :func:`worker_count`). The kernel's first arguments are the worker's index, the
    number of workers and ``sync`` (:func:`worker_sync`; its spin limits set here to
    :data:`WORKER_SPINS` and :data:`YIELD_AFTER_SPINS`); ``inputs`` are the rest. The workers meet at
    :func:`worker_barrier`. Every launch is prepared before any runs, so that none can fail
    while the others wait for it. One worker is a plain launch. Raises
    :class:`~party.errors.WorkersLost` where a worker waited in vain."""
    device = wp.get_device(device)
    sync.max_spins, sync.yield_after = WORKER_SPINS, YIELD_AFTER_SPINS
    if workers <= 1:
        launch(kernel, 1, [0, 1, sync, *inputs], device=device)
        return
    commands = []
    for worker in range(workers):
        arguments = [worker, workers, sync, *inputs]
        commands.append(_recorded_launch(_call_key(kernel, 1, arguments, (), device), kernel, 1, arguments, (), device))
    others = [_thread_pool(workers - 1).submit(command.launch) for command in commands[1:]]
    commands[0].launch()
    for other in others:
        other.result()
    if int(sync.counters.numpy()[2]):
        sync.counters.zero_()
        raise WorkersLost(f"{kernel.key}: a worker thread waited {WORKER_SPINS} spins for the others; "
                          "rerun with PARTY_THREADS=1")


def _thread_pool(threads: int) -> ThreadPoolExecutor:
    """The pool of threads that run launches beside the calling thread, with at least ``threads``."""
    global _pool, _pool_threads
    if _pool is None or _pool_threads < threads:
        if _pool is not None:
            _pool.shutdown(wait=False)
        _pool = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="party-launch")
        _pool_threads = threads
    return _pool
