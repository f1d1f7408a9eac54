"""The launcher: kernel launches replayed where a call repeats, item-wise kernels split over the
CPU's cores, and workers launched one per core; it owns the caches these keep for the process.

Packing a kernel's arguments costs ``wp.launch`` some 40 us on the CPU, more than many of our
kernels take to run, and a step of a garment drape makes about a hundred launches. So each
distinct call (the same kernel and dimensions, the same array objects, scalar values and struct
fields) is recorded once (Warp's ``record_cmd=True``) and replayed after, some 6 us in all.

Warp runs a CPU launch's threads one after another on one core. A kernel whose thread
``first + wp.tid()`` writes only its own item's outputs (and at most sets flags to a constant)
gives the same result whichever order its items run in, so :meth:`Launcher.launch_items` cuts
its range into one chunk per thread and launches the chunks from a pool of Python threads at
once (Warp releases the interpreter lock while a CPU kernel runs), where one thread would take
longer than ``split_seconds`` (judged from the kernel's earlier launches: a handoff costs some
110 us). Warp's CPU atomics are plain read-modify-writes, so such a kernel must not accumulate
into shared memory; a counter it bumps may lose increments between chunks, though it stays
non-zero when any was made. On CUDA, and while a graph is being captured (a CPU graph replays on
one thread), every launch is one plain launch.
"""

from __future__ import annotations

import time
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Iterator, Sequence

import warp as wp

from ..errors import WorkersLost
from .calls import call_key
from .threads import CORES, thread_count
from .workers import WorkerSync


@dataclass(frozen=True)
class LaunchSettings:
    """How kernels are launched.

    Attributes:
        min_chunk: Fewest items worth a thread of their own.
        split_seconds: Shortest time on one thread [s] for which a launch is split over threads:
            the split saves half of it and costs some 110 us.
        max_recorded: Recorded launches kept (the least recently used go first). A recorded
            launch holds on to its arrays, so this bounds the memory that models no longer in
            use can keep; a garment drape's steps make about a hundred distinct calls.
        worker_spins: Spins at a worker barrier before a worker gives up on the others (a quarter
            of an hour, yielding at every spin past ``yield_after_spins``): a worker that never
            arrives is a bug, which this turns into an error rather than a hang.
        yield_after_spins: Spins (each a pause of some 10-40 ns) after which a waiting worker
            gives its core away (``sched_yield``) at every further spin. Most meetings take
            microseconds; a worker that waits much longer may be waiting for one that has no
            core (another process took it), and spinning would hold the core its partner needs
            until the scheduler's time slice ends.
    """

    min_chunk: int = 1024
    split_seconds: float = 4.0e-4
    max_recorded: int = 512
    worker_spins: int = (1 << 31) - 1
    yield_after_spins: int = 1000


class Launcher:
    """Launches kernels (see the module docstring) and owns what that keeps for the process: the
    recorded launches, each kernel's time per item, the kernels loaded, the thread pool."""

    def __init__(self, settings: LaunchSettings = LaunchSettings()) -> None:
        self.settings = settings
        self.recorded: OrderedDict[tuple, Any] = OrderedDict()
        self.item_seconds: dict[Any, float] = {}
        self.loaded: set[tuple[str, str]] = set()
        self._pool: ThreadPoolExecutor | None = None
        self._pool_threads = 0

    def reset(self) -> None:
        """Forget every recorded launch, timing and loaded kernel, and stop the thread pool."""
        self.recorded.clear()
        self.item_seconds.clear()
        self.loaded.clear()
        if self._pool is not None:
            self._pool.shutdown(wait=False)
        self._pool, self._pool_threads = None, 0

    def launch(self, kernel: Any, dim: int | tuple[int, ...], inputs: Sequence[Any], outputs: Sequence[Any] = (),
               device: Any = None) -> None:
        """``wp.launch(kernel, dim, inputs, outputs, device)``, replayed from a recorded launch
        when the same call was made before; calls with arguments of other kinds, and any while
        a graph is being captured, are plain launches."""
        device = wp.get_device(device)
        key = None if device.is_capturing else call_key(kernel, dim, inputs, outputs, device)
        if key is None:
            wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device)
        else:
            self._recorded_launch(key, kernel, dim, inputs, outputs, device).launch()

    def _recorded_launch(self, key: tuple | None, kernel: Any, dim: Any, inputs: Sequence[Any],
                         outputs: Sequence[Any], device: Any) -> Any:
        """The recorded launch kept for the call ``key``, recorded now if none was; one with
        ``key`` None is recorded and not kept."""
        command = self.recorded.get(key) if key is not None else None
        if command is None:
            command = wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device, record_cmd=True)
            if key is not None:
                self.recorded[key] = command
                if len(self.recorded) > self.settings.max_recorded:
                    self.recorded.popitem(last=False)
        else:
            self.recorded.move_to_end(key)
        return command

    def launch_items(self, kernel: Any, first: int, count: int, inputs: Sequence[Any], device: Any) -> None:
        """Launch ``kernel`` over items ``first`` .. ``first + count - 1``; the kernel's first
        argument is the item of thread 0 (its item is ``first + wp.tid()``), ``inputs`` the
        rest. See the module docstring for what such a kernel may write."""
        if count <= 0:
            return
        device = wp.get_device(device)
        threads = min(thread_count(), count // self.settings.min_chunk)
        key = (kernel.key, str(device))
        if device.is_cuda or device.is_capturing:
            self.launch(kernel, count, [first, *inputs], device=device)
            return
        if threads < 2 or key not in self.loaded:
            self.launch(kernel, count, [first, *inputs], device=device)
            self.loaded.add(key)  # the first launch compiles and loads the module, which threads must not race on
            return
        per_item = self.item_seconds.get(key)
        if per_item is None or per_item * count < self.settings.split_seconds:
            started = time.perf_counter()
            self.launch(kernel, count, [first, *inputs], device=device)
            seconds = (time.perf_counter() - started) / count
            self.item_seconds[key] = seconds if per_item is None else 0.9 * per_item + 0.1 * seconds
            return
        pool = self._thread_pool(threads - 1)
        bounds = [first + count * k // threads for k in range(threads + 1)]
        others = [pool.submit(self.launch, kernel, bounds[k + 1] - bounds[k], [bounds[k], *inputs], device=device)
                  for k in range(1, threads)]
        self.launch(kernel, bounds[1] - bounds[0], [bounds[0], *inputs], device=device)
        for other in others:
            other.result()

    def worker_count(self, items: int, device: Any = None) -> int:
        """Workers :meth:`launch_workers` should use for ``items`` items per pass: up to
        :func:`~party.launch.thread_count` on the CPU, but no more than the cores this process
        may use (a worker spinning at a barrier holds its core, so one waiting for a core would
        stall the others for the scheduler's time slice), at least ``min_chunk`` items each; 1
        on CUDA."""
        if wp.get_device(device).is_cuda:
            return 1
        return max(1, min(thread_count(), CORES, items // self.settings.min_chunk))

    def launch_workers(self, kernel: Any, workers: int, sync: WorkerSync, inputs: Sequence[Any],
                       device: Any = None) -> None:
        """Launch ``kernel`` once per worker (``dim=1``), each on its own CPU thread at once. The
        kernel's first arguments are the worker's index, the number of workers and ``sync``
        (:func:`~party.launch.worker_sync`; its spin limits set here from the settings);
        ``inputs`` are the rest. The workers meet at :func:`~party.launch.worker_barrier`. Every
        launch is prepared before any runs, so that none can fail while the others wait for it.
        One worker is a plain launch. Raises :class:`~party.errors.WorkersLost` where a worker
        waited in vain."""
        device = wp.get_device(device)
        sync.max_spins, sync.yield_after = self.settings.worker_spins, self.settings.yield_after_spins
        if workers <= 1:
            self.launch(kernel, 1, [0, 1, sync, *inputs], device=device)
            return
        commands = []
        for worker in range(workers):
            arguments = [worker, workers, sync, *inputs]
            commands.append(self._recorded_launch(call_key(kernel, 1, arguments, (), device), kernel, 1, arguments,
                                                  (), device))
        others = [self._thread_pool(workers - 1).submit(command.launch) for command in commands[1:]]
        commands[0].launch()
        for other in others:
            other.result()
        if int(sync.counters.numpy()[2]):
            sync.counters.zero_()
            raise WorkersLost(f"{kernel.key}: a worker thread waited {self.settings.worker_spins} spins for the "
                              "others; rerun with PARTY_THREADS=1")

    def _thread_pool(self, threads: int) -> ThreadPoolExecutor:
        """The pool of threads that run launches beside the calling thread, with at least ``threads``."""
        if self._pool is None or self._pool_threads < threads:
            if self._pool is not None:
                self._pool.shutdown(wait=False)
            self._pool = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="party-launch")
            self._pool_threads = threads
        return self._pool


_current = Launcher()


def current() -> Launcher:
    """The launcher party's kernels are launched through."""
    return _current


@contextmanager
def using(launcher: Launcher) -> Iterator[Launcher]:
    """Launch through ``launcher`` within the ``with`` block (other settings, a fresh cache)."""
    global _current
    before, _current = _current, launcher
    try:
        yield launcher
    finally:
        _current = before
