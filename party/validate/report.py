"""The report of ``party validate``: a table on the terminal and ``results.json``."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Callable

from ..output.frames import write_json
from .checks import CaseResult, Check


def _number(x: float) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    if x == 0.0:
        return "0"
    if abs(x) >= 1e4 or abs(x) < 1e-3:
        return f"{x:.3e}"
    return f"{x:.4g}"


def print_table(results: list[CaseResult], console) -> None:
    """One row per check: case, quantity, simulated, reference, error, tolerance, pass/fail."""
    from rich.markup import escape
    from rich.table import Table

    table = Table(title="party validate")
    for column in ("case", "quantity", "simulated", "reference", "error", "tolerance", "result"):
        table.add_column(column, justify="right" if column in ("simulated", "reference", "error", "tolerance") else "left")
    for result in results:
        if "skipped" in result.details:
            table.add_row(result.name, escape(result.details["skipped"]), "", "", "", "", "[yellow]skipped[/]")
        for c in result.checks:
            error = _error_text(c)
            verdict = "reported" if c.error_kind == "reported" else ("[green]pass[/]" if c.passed else "[red]FAIL[/]")
            table.add_row(c.case, escape(c.quantity), _number(c.simulated), _number(c.reference), error, _number(c.tolerance),
                          verdict)
    if not console.is_terminal:  # a pipe or a log file: do not squeeze the table into 80 columns
        from rich.console import Console

        console = Console(file=console.file, width=160)
    console.print(table)


def _error_text(check) -> str:
    """The error column: a number, with its kind where it is not a relative error; for a
    yes/no decision whether it was right."""
    if check.error_kind == "wrong decision":
        return "right" if check.passed else "wrong"
    if check.error_kind in ("relative", "reported"):
        return _number(check.error)
    return f"{_number(check.error)} ({check.error_kind})"


def write_results(results: list[CaseResult], path: Path, settings: dict, complete: bool = True) -> None:
    """``results.json``: the settings, and per case its checks, plots, figures and time;
    ``complete`` False while cases are still to run (written after each case, atomically)."""
    document = {
        "settings": settings,
        "complete": complete,
        "passed": all(r.passed for r in results),
        "cases": [{
            "case": r.name,
            "passed": r.passed,
            "wall_seconds": round(r.wall_seconds, 3),
            "checks": [c.to_dict() for c in r.checks],
            "plots": [str(p.relative_to(path.parent)) if p.is_relative_to(path.parent) else str(p) for p in r.plots],
            "details": r.details,
        } for r in results],
    }
    write_json(path, document, default=_plain)


def read_results(path: Path, settings: dict, warn: Callable[[str], None] = lambda line: None) -> dict[str, CaseResult]:
    """The cases ``results.json`` at ``path`` holds, by name, where it was written with the same
    ``settings`` (fabric, solver, resolution; the cases asked for may differ); none otherwise.
    A file that is not a validation record (unreadable, not JSON, another shape) keeps none,
    and ``warn`` is told so in one line."""
    if not path.exists():
        return {}
    try:
        document = json.loads(path.read_text())
        if json.dumps(document.get("settings"), sort_keys=True) != json.dumps(settings, sort_keys=True, default=_plain):
            warn(f"{path} was written with other settings; running every case")
            return {}  # compared as written: a NaN equals itself there
        kept = {}
        for case in document.get("cases", []):
            checks = [Check(**{k: (math.nan if v is None else v) for k, v in c.items()}) for c in case["checks"]]
            plots = [path.parent / p for p in case["plots"]]
            kept[case["case"]] = CaseResult(case["case"], checks, plots, case["details"], case["wall_seconds"])
    except (OSError, ValueError, TypeError, KeyError, AttributeError) as error:
        warn(f"{path} is not a validation record ({type(error).__name__}); running every case")
        return {}
    return kept


def _plain(value):
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    raise TypeError(f"cannot write {type(value).__name__} to JSON")


def figure(size: tuple[float, float]):
    """A matplotlib figure and axes drawn off screen."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=size)


def save(fig, path: Path, dpi: int = 120) -> Path:
    """Write ``fig`` to ``path`` (folders made) and close it."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def plot_rest_shape(simulated, reference, *, simulated_label: str, reference_label: str, title: str,
                    unit: str, scale: float, size=(5.0, 4.0)):
    """A simulated rest shape (dots) over its reference curve, both (x, z) [m], drawn in
    ``unit`` (``scale`` per metre). Returns the figure and its axes, for additions."""
    fig, ax = figure(size)
    ax.plot(reference[:, 0] * scale, reference[:, 1] * scale, "k-", lw=1, label=reference_label)
    ax.plot(simulated[:, 0] * scale, simulated[:, 1] * scale, "o", ms=3, color="tab:red", label=simulated_label)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x [{unit}]")
    ax.set_ylabel(f"z [{unit}]")
    ax.set_title(title)
    return fig, ax
