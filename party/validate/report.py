"""The report of ``party validate``: a table on the terminal and ``results.json``."""

from __future__ import annotations

import json
import math
from pathlib import Path

from .checks import CaseResult


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
    from rich.table import Table

    table = Table(title="party validate")
    for column in ("case", "quantity", "simulated", "reference", "error", "tolerance", "result"):
        table.add_column(column, justify="right" if column in ("simulated", "reference", "error", "tolerance") else "left")
    for result in results:
        if "skipped" in result.details:
            table.add_row(result.name, result.details["skipped"], "", "", "", "", "[yellow]skipped[/]")
        for c in result.checks:
            error = _number(c.error) if c.error_kind in ("relative", "reported") else f"{_number(c.error)} ({c.error_kind})"
            verdict = "reported" if c.error_kind == "reported" else ("[green]pass[/]" if c.passed else "[red]FAIL[/]")
            table.add_row(c.case, c.quantity, _number(c.simulated), _number(c.reference), error, _number(c.tolerance),
                          verdict)
    console.print(table)


def write_results(results: list[CaseResult], path: Path, settings: dict) -> None:
    """``results.json``: the settings, and per case its checks, plots, figures and time."""
    document = {
        "settings": settings,
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
    path.write_text(json.dumps(document, indent=1, default=_plain))


def _plain(value):
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    raise TypeError(f"cannot write {type(value).__name__} to JSON")
