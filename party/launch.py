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
"""

from __future__ import annotations

import os
import time
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Sequence

import warp as wp

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
    (other array kinds: the same address, shape and strides) and the same scalar values. Calls
    with other arguments (structs), and any while a graph is being captured, are plain
    launches."""
    device = wp.get_device(device)
    key = None if device.is_capturing else _call_key(kernel, dim, inputs, outputs, device)
    if key is None:
        wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device)
        return
    command = _recorded.get(key)
    if command is None:
        command = wp.launch(kernel, dim=dim, inputs=inputs, outputs=outputs, device=device, record_cmd=True)
        _recorded[key] = command
        if len(_recorded) > MAX_RECORDED:
            _recorded.popitem(last=False)
    else:
        _recorded.move_to_end(key)
    command.launch()


def _call_key(kernel: Any, dim: Any, inputs: Sequence[Any], outputs: Sequence[Any], device: Any) -> tuple | None:
    """What identifies a call's packed arguments; None where an argument is of a kind not
    covered (it is then launched plainly)."""
    parts: list[Any] = [kernel, dim, device.alias]
    for arg in (*inputs, *outputs):
        kind = type(arg)
        if kind is wp.array:
            parts.append(id(arg))  # the record holds on to the array, so no other object can take its id
        elif kind in _SCALARS:
            parts.append((kind, arg))
        elif isinstance(arg, wp.array):
            parts.append((arg.ptr, arg.shape, arg.strides))
        elif hasattr(arg, "_length_"):  # Warp's vector and matrix values
            parts.append((type(arg), tuple(arg)))
        else:
            return None
    return tuple(parts)


def thread_count() -> int:
    """Threads :func:`launch_items` uses on the CPU: ``$PARTY_THREADS``, else the cores this
    process may use."""
    given = os.environ.get("PARTY_THREADS")
    if given:
        try:
            return max(int(given), 1)
        except ValueError:
            from .errors import InvalidInput

            raise InvalidInput(f"PARTY_THREADS must be a whole number, got {given!r}") from None
    return max(_CORES, 1)


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
    global _pool, _pool_threads
    if _pool_threads < threads - 1:
        if _pool is not None:
            _pool.shutdown(wait=False)
        _pool = ThreadPoolExecutor(max_workers=threads - 1, thread_name_prefix="party-launch")
        _pool_threads = threads - 1
    bounds = [first + count * k // threads for k in range(threads + 1)]
    others = [_pool.submit(launch, kernel, bounds[k + 1] - bounds[k], [bounds[k], *inputs], device=device)
              for k in range(1, threads)]
    launch(kernel, bounds[1] - bounds[0], [bounds[0], *inputs], device=device)
    for other in others:
        other.result()
