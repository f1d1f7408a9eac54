"""How the implicit step's cost grows with the node count.

    python benchmarks/scaling.py [--sizes 1000 2000 ... 100000] [--steps 30] [--self-collision]

A square of cotton resting on a sphere (as in ``party run sphere-drop``, started just above
the sphere so contacts are live) at each size; prints milliseconds per step after a warm-up,
and the cost per doubling relative to linear growth (1.0 = linear) between neighbouring sizes.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import warp as wp

from party.body import sphere
from party.collision import CollisionSettings
from party.fabric import fabric_by_name
from party.meshing import rectangular_net
from party.model import ModelBuilder
from party.solvers.select import DEFAULT_DT, make_solver


def step_ms(nodes: int, steps: int, self_collision: bool) -> tuple[int, float]:
    side = int(round(np.sqrt(nodes)))
    net = rectangular_net(1.0, 1.0, 1.0 / (side - 1))
    builder = ModelBuilder()
    builder.add_cloth(net, fabric_by_name("cotton"), np.c_[net.uv - 0.5, np.full(net.node_count, 0.305)])
    builder.add_collider(sphere(0.3, subdivisions=4))
    model = builder.finalize()
    solver = make_solver("implicit", model, collision=CollisionSettings(cloth=self_collision))
    state, scratch, control = model.state(), model.state(), model.control()
    for _ in range(5):
        solver.step(state, scratch, control, DEFAULT_DT["implicit"])
        state, scratch = scratch, state
    wp.synchronize()
    start = time.perf_counter()
    for _ in range(steps):
        solver.step(state, scratch, control, DEFAULT_DT["implicit"])
        state, scratch = scratch, state
    wp.synchronize()
    return model.node_count, 1000.0 * (time.perf_counter() - start) / steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 2000, 4000, 8000, 16000, 32000, 64000, 100000])
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--self-collision", action="store_true")
    args = parser.parse_args()
    rows = [step_ms(n, args.steps, args.self_collision) for n in args.sizes]
    print(f"{'nodes':>8} {'ms/step':>9} {'per doubling vs linear':>24}")
    for k, (n, ms) in enumerate(rows):
        growth = ""
        if k:
            n0, ms0 = rows[k - 1]
            growth = f"{(ms / ms0) ** (np.log(2) / np.log(n / n0)) / 2.0:.2f}"
        print(f"{n:>8} {ms:>9.2f} {growth:>24}")


if __name__ == "__main__":
    main()
