"""Launching kernels: every launch goes through here (:class:`Launcher`): replayed where a call
repeats, item-wise kernels split over the CPU's cores, and workers that meet at barriers. The
results are the same bit for bit however many threads run them."""

from __future__ import annotations

from typing import Any, Sequence

from .launcher import LaunchSettings, Launcher, current, using
from .threads import CORES, thread_count
from .workers import SCHED_YIELD, WorkerSync, worker_barrier, worker_sync


def launch(kernel: Any, dim: int | tuple[int, ...], inputs: Sequence[Any], outputs: Sequence[Any] = (),
           device: Any = None) -> None:
    """:meth:`Launcher.launch` of the current launcher."""
    current().launch(kernel, dim, inputs, outputs, device)


def launch_items(kernel: Any, first: int, count: int, inputs: Sequence[Any], device: Any) -> None:
    """:meth:`Launcher.launch_items` of the current launcher."""
    current().launch_items(kernel, first, count, inputs, device)


def launch_workers(kernel: Any, workers: int, sync: WorkerSync, inputs: Sequence[Any], device: Any = None) -> None:
    """:meth:`Launcher.launch_workers` of the current launcher."""
    current().launch_workers(kernel, workers, sync, inputs, device)


def worker_count(items: int, device: Any = None) -> int:
    """:meth:`Launcher.worker_count` of the current launcher."""
    return current().worker_count(items, device)


__all__ = ["CORES", "SCHED_YIELD", "LaunchSettings", "Launcher", "WorkerSync", "current", "launch", "launch_items",
           "launch_workers", "thread_count", "using", "worker_barrier", "worker_count", "worker_sync"]
