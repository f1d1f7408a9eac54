"""Running a batch: its items drape in a local pool of worker processes, or as Ray tasks.

Layout of the dataset folder::

    DATASET/<pattern>__<body>__<fabric>/   what ``party drape`` writes, one folder per item
    DATASET/manifest.parquet               one row per item done (:mod:`.manifest`)
    DATASET/logs/<item>.txt                each drape's terminal output
    DATASET/contact_sheet.png              every item's front view with its status (:mod:`.report`)

Local by default: ``workers`` items at a time, each a ``party drape`` process with its share of
the cores as kernel threads (:mod:`.worker`). With ``ray`` (an address, or "auto": the running
cluster, else a local one), each item is a Ray task running that same process, which needs one
CPU per thread; on a cluster of several machines the dataset folder must be on storage they
share. Either way the manifest is rewritten as each item finishes, and a batch resumed after a
kill skips the items in it and goes on with each unfinished drape from its checkpoint.
"""

from __future__ import annotations

from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Iterator

from ..errors import InvalidInput
from ..launch.threads import CORES
from ..resources import check_time_limit
from .items import BatchItem
from .manifest import Manifest
from .worker import Interrupted, ItemOptions, run_item


@dataclass(frozen=True)
class BatchSettings:
    """How a batch runs.

    Attributes:
        workers: Items draped at once (None: one per core; with Ray, as many as the cluster's
            CPUs take).
        threads: Kernel threads of each item (None: the cores shared among the local workers;
            one with Ray).
        ray: A Ray cluster's address, or "auto"; None runs locally.
        resume: Skip the items the manifest holds; go on with the others.
        item: How each item is draped (its ``threads`` set from the above).
    """

    workers: int | None = None
    threads: int | None = None
    ray: str | None = None
    resume: bool = False
    item: ItemOptions = field(default_factory=ItemOptions)

    def __post_init__(self) -> None:
        if self.workers is not None and self.workers < 1:
            raise InvalidInput(f"--workers must be at least 1, got {self.workers}")
        if self.threads is not None and self.threads < 1:
            raise InvalidInput(f"threads per worker must be at least 1, got {self.threads}")
        check_time_limit(self.item.time_limit)

    def local_pool(self) -> tuple[int, int]:
        """(workers, threads per worker) of a local run."""
        workers = self.workers or max(CORES, 1)
        return workers, self.threads or max(CORES // workers, 1)


Done = Callable[[BatchItem, dict], None]
"""``on_done(item, row)``: an item finished with its manifest ``row``."""


def run_batch(items: list[BatchItem], dataset: Path, settings: BatchSettings, *, on_done: Done | None = None,
              on_start: Callable[[int, int], None] | None = None) -> Manifest:
    """Drape every item not yet done into ``dataset`` (an output folder already taken) and
    return the manifest. ``on_start(total, done)`` is told the batch's size and the items a
    resume skips; ``on_done`` hears of each item as it is recorded. A Ctrl-C stops the batch
    after the drapes running stop (each keeps its checkpoint) and raises KeyboardInterrupt."""
    manifest = Manifest(dataset / "manifest.parquet", [i.name for i in items])
    if settings.resume:
        manifest.load()
    todo = [i for i in items if i.name not in manifest]
    if on_start is not None:
        on_start(len(items), len(items) - len(todo))
    finished = _ray(todo, dataset, settings) if settings.ray else _local(todo, dataset, settings)
    for item, row in finished:
        manifest.add(row)
        if on_done is not None:
            on_done(item, row)
    manifest.write()
    return manifest


def _local(items: list[BatchItem], dataset: Path, settings: BatchSettings) -> Iterator[tuple[BatchItem, dict]]:
    """Each item's row as it finishes, ``settings.local_pool()`` at a time."""
    workers, threads = settings.local_pool()
    options = _with_threads(settings.item, threads)
    with ThreadPoolExecutor(max_workers=workers) as pool:
        running = {}
        queue = iter(items)
        try:
            for item in queue:
                running[pool.submit(run_item, item, dataset, options)] = item
                if len(running) >= workers:
                    break
            while running:
                done, _ = wait(running, return_when=FIRST_COMPLETED)
                for future in done:
                    item = running.pop(future)
                    yield item, _row(item, future)
                    following = next(queue, None)
                    if following is not None:
                        running[pool.submit(run_item, following, dataset, options)] = following
        except (Interrupted, KeyboardInterrupt):
            for future in running:
                future.cancel()
            wait(running)
            raise KeyboardInterrupt from None


def _row(item: BatchItem, future) -> dict:
    """The row an item's future holds; an error row where the batch itself could not run it (a
    full disk for its log, say), so that one item's trouble never ends the batch."""
    try:
        return future.result()
    except (Interrupted, KeyboardInterrupt):
        raise
    except Exception as error:
        return error_row(item, f"the batch could not run it ({type(error).__name__}: {error})")


def error_row(item: BatchItem, reason: str) -> dict:
    """A manifest row of an item that ended in error for ``reason``."""
    return item.columns() | {"status": "error", "reasons": [reason]}


def _ray(items: list[BatchItem], dataset: Path, settings: BatchSettings) -> Iterator[tuple[BatchItem, dict]]:
    """Each item's row as its Ray task finishes."""
    try:
        import ray
    except ImportError:
        raise InvalidInput("--ray needs Ray: pip install 'party[ray]'") from None
    if not ray.is_initialized():
        if settings.ray == "auto":
            try:
                ray.init(address="auto", logging_level="ERROR", log_to_driver=False)
            except ConnectionError:
                ray.init(logging_level="ERROR", log_to_driver=False, include_dashboard=False)
        else:
            try:
                ray.init(address=settings.ray, logging_level="ERROR", log_to_driver=False)
            except (ConnectionError, ValueError, RuntimeError) as error:
                raise InvalidInput(f"--ray {settings.ray}: cannot reach a Ray cluster there ({error})") from None
    threads = settings.threads or 1
    options = _with_threads(settings.item, threads)
    task = ray.remote(num_cpus=threads, max_retries=0)(run_item)
    queue = iter(items)
    pending = {}

    def submit() -> None:
        following = next(queue, None)
        if following is not None:
            pending[task.remote(following, dataset, options)] = following

    for _ in range(settings.workers or len(items)):
        submit()
    try:
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                item = pending.pop(ref)
                submit()
                try:
                    row = ray.get(ref)
                except ray.exceptions.RayError as error:
                    row = error_row(item, f"its Ray task failed ({type(error).__name__})")
                yield item, row
    except KeyboardInterrupt:
        for ref in pending:
            ray.cancel(ref)
        raise


def _with_threads(options: ItemOptions, threads: int) -> ItemOptions:
    return replace(options, threads=threads)
