"""party's implicit solver on a CUDA GPU against the CPU, the same sphere drop in one run.

    python benchmarks/gpu.py [--grids 100 316] [--self-collision off on] [--seconds 1]
                             [--devices cpu cuda]

Runs scene (a) of ``benchmarks/compare.py`` (``party run sphere-drop``: a 1 m cloth of N x N
nodes dropped onto a sphere) with the implicit solver on each device, the same kernels on both,
and prints per scene wall seconds per simulated second on each (the first frame's steps, with
the kernels' compilation, apart), the GPU's speed-up over the CPU, and the outcome on each
(smallest distance from the sphere's centre, nodes inside, cloth crossings, height range), so
that the two can be seen to agree. Stops with one line where no CUDA device is present.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--grids", type=int, nargs="+", default=[100, 316])
    parser.add_argument("--self-collision", nargs="+", choices=["off", "on"], default=["off", "on"])
    parser.add_argument("--seconds", type=float, default=1.0, help="simulated seconds of each drop")
    parser.add_argument("--devices", nargs="+", choices=["cpu", "cuda"], default=["cpu", "cuda"])
    args = parser.parse_args()
    if not args.seconds >= 0.1:
        parser.error(f"--seconds must be at least 0.1, got {args.seconds}")
    import warp as wp

    from compare import describe, party_sphere
    from party.device import init

    init()
    if "cuda" in args.devices and not wp.is_cuda_available():
        raise SystemExit("no CUDA device here: run with --devices cpu, or on a machine with an NVIDIA GPU")
    if "cuda" in args.devices:
        print(f"GPU: {wp.get_cuda_device().name}; CPU threads: party.launch's default", flush=True)
    for grid in args.grids:
        for self_collision in args.self_collision:
            scene = f"sphere-drop {grid}x{grid} self {self_collision}"
            seconds = {}
            for device in args.devices:
                print(f"{scene} on {device} ...", flush=True)
                row = party_sphere("implicit", grid, self_collision == "on", args.seconds, None, device)
                seconds[device] = row["wall_per_simulated_second"]
                print(f"    {describe(row)}", flush=True)
            if len(seconds) == 2:
                print(f"{scene}: the GPU is {seconds['cpu'] / seconds['cuda']:.1f}x as fast as the CPU", flush=True)


if __name__ == "__main__":
    sys.path.insert(0, str(HERE.parent))
    sys.path.insert(0, str(HERE))
    main()
