"""Explicit step speed: a square cloth of about 1k, 10k and 100k nodes over a sphere.

    python benchmarks/explicit_step.py [--sizes 1000 10000 100000] [--steps 200] [--device cpu]

Prints, per size, steps per second of the paper's explicit step (eqs. 3-5) without collision,
with cloth-body collision, and with body and cloth-cloth collision, and the ratio of each
collision mode to the collision-free step measured in the same run. Compile time is excluded
(a warm-up step runs first). The cloth starts 1 cm above the sphere's top and drapes during
the measured steps, so contacts are live.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import warp as wp

from party import device as devices
from party.body import sphere
from party.collision import CollisionSettings
from party.fabric import wool_flannel
from party.meshing import rectangular_net
from party.model import ModelBuilder
from party.solvers import SolverExplicit

MODES = {"none": None, "body": CollisionSettings(cloth=False), "body+cloth": CollisionSettings()}


def build(nodes: int, device: str):
    side = int(round(np.sqrt(nodes)))
    spacing = 0.01
    fabric = wool_flannel()
    net = rectangular_net(spacing * (side - 1), spacing * (side - 1), spacing)
    radius = 0.3 * net.uv.max() / 1.0
    b = ModelBuilder()
    b.add_cloth(net, fabric, np.c_[net.uv - net.uv.max() / 2, np.full(net.node_count, radius + 0.01)])
    b.add_collider(sphere(radius, subdivisions=5))
    return b.finalize(device)


def steps_per_second(model, settings, steps: int, dt: float = 1.0e-4) -> float:
    solver = SolverExplicit(model, collision=settings)
    state, scratch = model.state(), model.state()
    control = model.control()
    for _ in range(20):  # compile and warm up
        solver.step(state, scratch, control, dt)
        state, scratch = scratch, state
    wp.synchronize_device(model.device)
    start = time.perf_counter()
    for _ in range(steps):
        solver.step(state, scratch, control, dt)
        state, scratch = scratch, state
    wp.synchronize_device(model.device)
    return steps / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000, 100000])
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--device", default="cpu")
    args = parser.parse_args()
    device = devices.resolve(args.device)
    print(f"device {device}; dt = 1e-4 s; steps per second (ratio to the collision-free step)")
    print(f"{'nodes':>8} {'none':>10} {'body':>18} {'body+cloth':>18}")
    for size in args.sizes:
        model = build(size, device)
        steps = max(10, args.steps * 10000 // max(size, 10000))
        rates = {name: steps_per_second(model, settings, steps) for name, settings in MODES.items()}
        base = rates["none"]
        print(f"{model.node_count:>8} {base:>10.1f} " + " ".join(
            f"{rates[m]:>9.1f} ({rates[m] / base:5.3f})" for m in ("body", "body+cloth")), flush=True)


if __name__ == "__main__":
    main()
