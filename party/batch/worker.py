"""One item of a batch: ``party drape`` in a process of its own, and its manifest row.

Each item runs as its own ``party drape`` process, so that whatever happens to it (bad input,
a blow-up, a crash in native code, the kernel's out-of-memory killer, a hang) ends that process
only: the batch reads its exit status and ``summary.json`` and goes on. A process that outlives
its time limit by :data:`GRACE` (the drape stops itself at the limit, so it hangs) is killed.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from ..errors import INTERRUPTED
from .items import BatchItem

GRACE = 1.5
"""A drape still running at this multiple of its time limit, plus :data:`GRACE_SECONDS`, hangs
and is killed: it stops itself at its limit, and writing its results takes seconds."""

GRACE_SECONDS = 120.0
"""See :data:`GRACE` [s]."""

@dataclass(frozen=True)
class ItemOptions:
    """How each item is draped: ``party drape``'s options. ``threads``: CPU threads of its
    kernels (``PARTY_THREADS``)."""

    spacing_mm: float = 20.0
    solver: str = "explicit"
    time_limit: float = 600.0
    images: bool = True
    threads: int = 1
    device: str | None = None


class Interrupted(Exception):
    """An item's drape was stopped by Ctrl-C (its checkpoint kept for ``--resume``)."""


def drape_command(item: BatchItem, folder: Path, options: ItemOptions) -> list[str]:
    """The ``party drape`` command line of ``item`` into ``folder``; it goes on from the
    folder's checkpoint where a killed batch left one."""
    command = [sys.executable, "-m", "party.cli", "drape", str(item.pattern), "--body", item.body,
               "--fabric", item.fabric, "--out", str(folder), "--spacing-mm", f"{options.spacing_mm:g}",
               "--solver", options.solver, "--time-limit", f"{options.time_limit:g}", "--no-progress"]
    if not options.images:
        command.append("--no-images")
    if options.device:
        command += ["--device", options.device]
    if (folder / "checkpoint.npz").exists():
        command.append("--resume")
    return command


def run_item(item: BatchItem, dataset: Path, options: ItemOptions) -> dict:
    """Drape ``item`` into ``dataset/<item.name>/`` and return its manifest row
    (:data:`party.batch.manifest.SCHEMA`); its output goes to ``dataset/logs/<item.name>.txt``.
    Raises :class:`Interrupted` where the drape was stopped by Ctrl-C."""
    folder = Path(dataset) / item.name
    log = Path(dataset) / "logs" / f"{item.name}.txt"
    log.parent.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, PARTY_THREADS=str(options.threads), PYTHONUNBUFFERED="1")
    env.pop("PARTY_TRACEBACK", None)
    started = time.perf_counter()
    with open(log, "w") as out:
        process = subprocess.Popen(drape_command(item, folder, options), stdout=out, stderr=subprocess.STDOUT,
                                   env=env)
        try:
            code = process.wait(timeout=GRACE * options.time_limit + GRACE_SECONDS)
            hung = False
        except subprocess.TimeoutExpired:
            process.kill()
            code = process.wait()
            hung = True
        except BaseException:
            process.send_signal(signal.SIGINT)
            process.wait()
            raise
    wall = time.perf_counter() - started
    row = item.columns() | {"wall_seconds": round(wall, 2)}
    if code == INTERRUPTED:  # stopped by Ctrl-C: not done, and the batch stops
        raise Interrupted(item.name)
    if hung:
        return row | {"status": "timeout", "reasons": [f"still running {wall:.0f} s after it started; killed"]}
    if code != 0:
        return row | {"status": "error", "reasons": [_failure(code, log)]}
    try:
        summary = json.loads((folder / "summary.json").read_text())
    except (OSError, ValueError) as error:
        return row | {"status": "error", "reasons": [f"no readable summary.json ({error})"]}
    return row | summary_columns(summary)


def summary_columns(summary: dict) -> dict:
    """A finished drape's manifest columns from its ``summary.json``."""
    quality = summary["quality"]
    timed_out = any(r.startswith("ran past") for r in quality["reasons"])
    status = "passed" if quality["passed"] else "timeout" if timed_out else "failed"
    return {"status": status, "reasons": list(quality["reasons"]), "nodes": summary["nodes"],
            "wall_seconds": summary["wall_seconds"], "max_seam_gap_mm": summary["max_seam_gap_mm"],
            "max_elongation": summary["max_elongation"], "body_penetrations": summary["body_penetrations"],
            "cloth_crossings": summary["cloth_crossings"], "at_rest": summary["relaxation"]["at_rest"],
            "draping_steps": summary["relaxation"]["draping_steps"],
            "nearest_body_mm": summary["body_distance_mm"]["nearest"],
            "median_body_mm": summary["body_distance_mm"]["median"]}


def _failure(code: int, log: Path) -> str:
    """One line for a drape that exited with ``code``: party's own error line where it wrote
    one, else how the process ended."""
    if code < 0:
        name = signal.Signals(-code).name
        hint = " (out of memory?)" if -code == signal.SIGKILL else ""
        return f"killed by {name}{hint}"
    lines = log.read_text(errors="replace").splitlines()
    said = [line for line in lines if line.startswith("error:")]
    return said[-1].removeprefix("error:").strip() if said else f"exited with status {code}"
