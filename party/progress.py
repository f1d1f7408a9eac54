"""Progress bars for long set-up work (sewing, draping), shown on the terminal with rich."""

from __future__ import annotations

from contextlib import contextmanager


@contextmanager
def relax_progress(label: str, total: int, show: bool):
    """A progress bar for a relaxation of at most ``total`` iterations; yields the ``on_log``
    callback to hand to it (``on_log(iteration, energy [J], state)``)."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    bar = Progress(TextColumn(f"[bold]{label}[/]"), BarColumn(), TextColumn("{task.completed} iterations"),
                   TextColumn("energy {task.fields[energy]:.4g} J"), TimeElapsedColumn(), disable=not show)
    with bar:
        task = bar.add_task(label, total=total, energy=float("nan"))

        def on_log(iteration: int, energy: float, state) -> None:
            bar.update(task, completed=iteration, energy=energy)

        yield on_log
        bar.update(task, total=bar.tasks[0].completed)
