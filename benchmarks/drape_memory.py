"""Peak memory of ``party drape`` against the node count, and the footprint party plans with.

    python benchmarks/drape_memory.py [--pattern FILE] [--body FILE] [--spacings 40 20 12 8]
                                      [--out DIR] [--solver explicit|implicit]

Drapes the pattern (default: GarmentCode's jumpsuit on ``mean_all``, both from ``../shared``)
at each spacing in a process of its own, without images, and prints its nodes, its peak
resident memory (the kernel's ``ru_maxrss`` of that process), its wall time and what
:data:`party.resources.DRAPE_FOOTPRINT` plans for that many nodes: the plan must lie above
every measurement (``party drape`` refuses a garment whose plan does not fit the machine's
free memory), and a least-squares line through the measurements says how far above.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from party.resources import DRAPE_FOOTPRINT

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "garmentcode"


def measure(pattern: Path, body: Path, spacing_mm: float, out: Path, solver: str) -> tuple[int, float, float]:
    """(nodes, peak resident memory [bytes], wall seconds) of one drape in its own process."""
    command = [sys.executable, "-m", "party.cli", "drape", str(pattern), "--body", str(body), "--out", str(out),
               "--spacing-mm", f"{spacing_mm:g}", "--solver", solver, "--no-images", "--no-progress",
               "--overwrite"]
    started = time.perf_counter()
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - started
    if status != 0:
        raise SystemExit(f"drape at {spacing_mm} mm failed: {child.stderr.read().strip()}")
    nodes = json.loads((out / "summary.json").read_text())["nodes"]
    return nodes, usage.ru_maxrss * 1024.0, wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pattern", type=Path, default=SHARED / "patterns" / "js_mean_all_specification.json")
    parser.add_argument("--body", type=Path, default=SHARED / "bodies" / "mean_all.obj")
    parser.add_argument("--spacings", type=float, nargs="+", default=[40.0, 20.0, 12.0, 8.0])
    parser.add_argument("--solver", default="explicit")
    parser.add_argument("--out", type=Path, default=Path("out/drape_memory"))
    args = parser.parse_args()
    rows = []
    print(f"{'spacing mm':>10} {'nodes':>7} {'peak MB':>8} {'planned MB':>10} {'wall s':>7}")
    for spacing in args.spacings:
        nodes, peak, wall = measure(args.pattern, args.body, spacing, args.out / f"{spacing:g}mm", args.solver)
        rows.append((nodes, peak))
        print(f"{spacing:>10g} {nodes:>7} {peak / 1e6:>8.0f} {DRAPE_FOOTPRINT.bytes(nodes) / 1e6:>10.0f} {wall:>7.0f}",
              flush=True)
    nodes, peak = np.array(rows, dtype=float).T
    if len(rows) > 1:
        slope, base = np.polyfit(nodes, peak, 1)
        print(f"fit: {base / 1e6:.0f} MB + {slope / 1e3:.1f} kB a node; planned: {DRAPE_FOOTPRINT.base / 1e6:.0f} MB + "
              f"{DRAPE_FOOTPRINT.per_node / 1e3:.1f} kB a node")
    under = [int(n) for n, p in rows if DRAPE_FOOTPRINT.bytes(int(n)) < p]
    print("the plan lies above every measurement" if not under else f"the plan lies BELOW the measurement at {under} nodes")


if __name__ == "__main__":
    main()
