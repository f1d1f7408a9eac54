"""Launching item-wise kernels on every CPU core.

Warp runs a CPU launch's threads one after another on one core. A kernel whose thread
``first + wp.tid()`` writes only its own item's outputs (and at most sets flags to a constant)
gives the same result whichever order its items run in, so :func:`launch_items` cuts its range
into one chunk per core and launches the chunks from a pool of Python threads at once: Warp
releases the interpreter lock while a CPU kernel runs. On CUDA, and while a graph is being
captured (a CPU graph replays its launches in order on one thread), it is one plain launch.

Warp's CPU atomics are plain read-modify-writes, so a kernel launched this way must not
accumulate into shared memory; a counter it bumps (``wp.atomic_add``) may lose increments
between chunks, though it stays non-zero when any was made. ``$PARTY_THREADS`` sets the number
of threads (default: the cores this process may use).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Sequence

import warp as wp

MIN_CHUNK = 1024
"""Fewest items worth a thread of their own: below this, handing a chunk to another thread
(some 20 us) costs more than it saves."""

_CORES = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
_pool: ThreadPoolExecutor | None = None
_pool_threads = 0
_loaded: set[tuple[str, str]] = set()


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
    if device.is_cuda or threads < 2 or key not in _loaded or device.is_capturing:
        wp.launch(kernel, dim=count, inputs=[first, *inputs], device=device)
        _loaded.add(key)  # the first launch compiles and loads the module, which threads must not race on
        return
    global _pool, _pool_threads
    if _pool_threads < threads - 1:
        if _pool is not None:
            _pool.shutdown(wait=False)
        _pool = ThreadPoolExecutor(max_workers=threads - 1, thread_name_prefix="party-launch")
        _pool_threads = threads - 1
    bounds = [first + count * k // threads for k in range(threads + 1)]
    others = [_pool.submit(wp.launch, kernel, dim=bounds[k + 1] - bounds[k], inputs=[bounds[k], *inputs],
                           device=device) for k in range(1, threads)]
    wp.launch(kernel, dim=bounds[1] - bounds[0], inputs=[bounds[0], *inputs], device=device)
    for other in others:
        other.result()
