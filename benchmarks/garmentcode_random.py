"""Random GarmentCode designs draped with ``party batch``: the pass rate under the quality gates.

    python benchmarks/garmentcode_random.py --seed S --count N [--body NAME] [--workers K]
                                            [--designs DIR] [--spacing-mm MM] [--solver NAME]
                                            [--time-limit S] [--out DIR] [--resume]

Samples N designs for the body with GarmentCode's own sampler (``../shared/tools/garmentcode_sampler``,
run by the Python of its own virtual environment: ``$GARMENTCODE_PYTHON``, else
``~/.venv-gc/bin/python``; its README says how to make it), or takes the designs of a folder of
``*_specification.json`` files (``--designs``), and drapes each on the body it was sampled for
(pants on the body with its legs apart, where there is one, as GarmentCode drapes them) with
``party batch``. Prints the pass rate, the failure reasons with their counts and the wall time
per garment (median, 90th percentile, largest), and writes every item's row to ``OUT/results.csv``.
Designs, drapes and manifests go under ``--out`` (default ``out/garmentcode_random``); ``--resume``
goes on with a batch that was stopped.
"""

from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from party.batch.report import reason_kind

SHARED = Path(__file__).resolve().parents[2] / "shared"
SAMPLER = SHARED / "tools" / "garmentcode_sampler" / "sample.py"
BODIES = SHARED / "data" / "garmentcode" / "bodies"


def sampler_python() -> str:
    python = os.environ.get("GARMENTCODE_PYTHON") or str(Path.home() / ".venv-gc" / "bin" / "python")
    if not Path(python).exists():
        raise SystemExit(f"no GarmentCode sampler environment at {python}: make it as "
                         f"{SAMPLER.parent / 'README.md'} says, or set GARMENTCODE_PYTHON, or pass --designs DIR")
    return python


def sample(seed: int, count: int, body: str, out: Path) -> None:
    """Sample ``count`` designs for ``body`` into ``out`` (kept where they are already there)."""
    names = [out / f"rand_{seed}_{k}_specification.json" for k in range(count)]
    if all(n.exists() for n in names):
        return
    out.mkdir(parents=True, exist_ok=True)
    print(f"sampling {count} designs for {body} (seed {seed}) ...", flush=True)
    subprocess.run([sampler_python(), str(SAMPLER), "--seed", str(seed), "--count", str(count), "--body", body,
                    "--out", str(out)], check=True, stdout=subprocess.DEVNULL)


def body_of(spec: Path, body: str) -> Path:
    """The body mesh ``spec`` drapes on: its design file's ``body_sample`` where that mesh
    exists (``mean_all_apart`` for pants), else ``body``."""
    design = spec.with_name(spec.name.replace("_specification.json", "_design.yaml"))
    if design.exists():
        for line in design.read_text().splitlines():
            if line.strip().startswith("body_sample:"):
                candidate = BODIES / f"{line.split(':', 1)[1].strip()}.obj"
                if candidate.exists():
                    return candidate
    return BODIES / f"{body}.obj"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--count", type=int, default=10)
    parser.add_argument("--body", default="mean_all", help="mean_all, mean_female or mean_male")
    parser.add_argument("--designs", type=Path, help="a folder of *_specification.json instead of sampling")
    parser.add_argument("--workers", type=int)
    parser.add_argument("--spacing-mm", type=float, default=20.0)
    parser.add_argument("--solver", default="explicit")
    parser.add_argument("--time-limit", type=float, default=600.0)
    parser.add_argument("--fabric", default="wool_flannel")
    parser.add_argument("--out", type=Path, default=Path("out/garmentcode_random"))
    parser.add_argument("--resume", action="store_true")
    args = parser.parse_args()

    if args.designs:
        specs = sorted(args.designs.glob("*_specification.json"))
        run = args.out / args.designs.name
    else:
        run = args.out / f"{args.body}_seed{args.seed}"
        sample(args.seed, args.count, args.body, run / "designs")
        specs = [run / "designs" / f"rand_{args.seed}_{k}_specification.json" for k in range(args.count)]
    if not specs:
        raise SystemExit("no designs to drape")
    groups: dict[Path, list[Path]] = {}
    for spec in specs:
        groups.setdefault(body_of(spec, args.body), []).append(spec)

    rows = []
    for body, group in groups.items():
        dataset = run / f"drapes_{body.stem}"
        command = [sys.executable, "-m", "party.cli", "batch", *map(str, group), "--bodies", str(body),
                   "--fabrics", args.fabric, "--out", str(dataset), "--spacing-mm", f"{args.spacing_mm:g}",
                   "--solver", args.solver, "--time-limit", f"{args.time_limit:g}", "--overwrite"]
        if args.workers:
            command += ["--workers", str(args.workers)]
        if args.resume:
            command.append("--resume")
        print(f"{len(group)} designs on {body.stem}", flush=True)
        subprocess.run(command, check=False)
        manifest = dataset / "manifest.parquet"
        if manifest.exists():
            rows += pq.read_table(manifest).to_pylist()

    write_csv(run / "results.csv", rows)
    report(rows, len(specs))
    print(f"rows in {run / 'results.csv'}")


def write_csv(path: Path, rows: list[dict]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        columns = list(rows[0]) if rows else ["item"]
        writer.writerow(columns)
        for row in rows:
            writer.writerow(["; ".join(row[c]) if isinstance(row[c], list) else row[c] for c in columns])


def report(rows: list[dict], designs: int) -> None:
    passed = sum(r["status"] == "passed" for r in rows)
    print(f"\npassed {passed} of {designs} designs ({100.0 * passed / max(designs, 1):.0f} %); "
          f"{designs - len(rows)} not draped")
    statuses = Counter(r["status"] for r in rows)
    print("by status: " + ", ".join(f"{s} {n}" for s, n in statuses.most_common()))
    reasons = Counter(reason_kind(x) for r in rows if r["status"] != "passed" for x in r["reasons"] or [])
    for reason, n in reasons.most_common():
        print(f"  {n:4d}  {reason}")
    wall = np.array([r["wall_seconds"] for r in rows if r["wall_seconds"] is not None])
    if len(wall):
        print(f"wall time per garment: median {np.median(wall):.0f} s, 90th percentile "
              f"{np.percentile(wall, 90):.0f} s, largest {wall.max():.0f} s")


if __name__ == "__main__":
    main()
