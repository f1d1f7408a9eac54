"""How the implicit step's cost grows with the node count.

    python benchmarks/scaling.py [--sizes 1000 2000 ... 100000] [--steps 30] [--repeats 3]
                                 [--self-collision] [--spacing M]

A square of cotton resting on a sphere (as in ``party run sphere-drop``, started just above
the sphere so contacts are live) at each size; prints milliseconds per step after a warm-up
(the least of ``--repeats`` runs of ``--steps`` steps, each from a fresh model: single runs on a
shared 2-core machine differed by up to a third at one size), the cost per doubling relative to
linear growth (1.0 = linear) between neighbouring sizes, and over the whole range the
exponent p of a least-squares fit ms ~ nodes^p, as its cost per doubling 2^(p - 1).
The square is 1 m across, so more nodes mean a finer net, or with ``--spacing`` its nodes are
that far apart and the square grows. In the 1 m square a finer net is stiffer for its inertia
(a node's K dt^2 / m grows as 1 / spacing^2), and from 64k nodes (4 mm) the implicit solver takes
more sweeps a step than its 10 (``STIFFNESS_PER_SWEEP`` in ``party.solvers.implicit.solver``;
printed per size); with self-collision each node's search also meets more triangles of its own
layer within the thickness (3 mm) plus margin (the cloth triangles kept per node, printed; the
margin narrows to a quarter of the element where the body's 4 mm would list the flat net's own
layer, ``CollisionPipeline.default_cloth_margin``). At a fixed spacing the cost per node stays
the same. ``benchmarks/step_profile.py square --nodes N`` shows where one size's step goes.
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
from party.model import Model, ModelBuilder
from party.solvers.implicit import SolverImplicit
from party.solvers.registry import make_solver, solver_class


def square_on_sphere(nodes: int, self_collision: bool,
                     spacing: float | None = None) -> tuple[Model, SolverImplicit, float]:
    """A square of cotton of about ``nodes`` nodes (1 m across, or ``spacing`` [m] between
    nodes) lying just above the sphere of ``party run sphere-drop``: the model, the implicit
    solver and its time step [s]."""
    side = int(round(np.sqrt(nodes)))
    size = 1.0 if spacing is None else spacing * (side - 1)
    net = rectangular_net(size, size, size / (side - 1))
    builder = ModelBuilder()
    builder.add_cloth(net, fabric_by_name("cotton"), np.c_[net.uv - 0.5 * size, np.full(net.node_count, 0.305)])
    builder.add_collider(sphere(0.3, subdivisions=4))
    model = builder.finalize()
    solver = make_solver("implicit", model, collision=CollisionSettings(cloth=self_collision))
    return model, solver, solver_class("implicit").default_dt


def step_ms(nodes: int, steps: int, self_collision: bool,
            spacing: float | None = None) -> tuple[int, int, float, float]:
    """Node count, sweeps a step, milliseconds a step of :func:`square_on_sphere` and the cloth
    triangles its collision search kept per node at the end (0 without self-collision)."""
    model, solver, dt = square_on_sphere(nodes, self_collision, spacing)
    state, scratch, control = model.state(), model.state(), model.control()
    for _ in range(5):
        solver.step(state, scratch, control, dt)
        state, scratch = scratch, state
    wp.synchronize()
    start = time.perf_counter()
    for _ in range(steps):
        solver.step(state, scratch, control, dt)
        state, scratch = scratch, state
    wp.synchronize()
    kept = solver.collision.cloth_candidate_count.numpy().mean() if self_collision else 0.0
    return model.node_count, solver.sweeps(dt), 1000.0 * (time.perf_counter() - start) / steps, float(kept)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 2000, 4000, 8000, 16000, 32000, 64000, 100000])
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--repeats", type=int, default=3, help="runs per size; the fastest counts")
    parser.add_argument("--self-collision", action="store_true")
    parser.add_argument("--spacing", type=float, default=None,
                        help="node spacing [m], the square growing with the node count (default: a 1 m square)")
    args = parser.parse_args()
    if args.repeats < 1 or args.steps < 1:
        parser.error(f"--repeats and --steps must be at least 1, got {args.repeats} and {args.steps}")
    rows, sweeps, kept = [], [], []
    for n in args.sizes:
        runs = [step_ms(n, args.steps, args.self_collision, args.spacing) for _ in range(args.repeats)]
        rows.append((runs[0][0], min(run[2] for run in runs)))
        sweeps.append(runs[0][1])
        kept.append(runs[0][3])
    print(f"{'nodes':>8} {'sweeps':>6} {'kept/node':>9} {'ms/step':>9} {'per doubling vs linear':>24}")
    for k, (n, ms) in enumerate(rows):
        growth = ""
        if k:
            n0, ms0 = rows[k - 1]
            growth = f"{(ms / ms0) ** (np.log(2) / np.log(n / n0)) / 2.0:.2f}"
        print(f"{n:>8} {sweeps[k]:>6} {kept[k]:>9.1f} {ms:>9.2f} {growth:>24}")
    if len(rows) > 1:
        nodes, ms = np.log(np.array(rows, dtype=float)).T
        exponent = np.polyfit(nodes, ms, 1)[0]
        print(f"fit over {rows[0][0]}-{rows[-1][0]} nodes: ms ~ nodes^{exponent:.3f}, "
              f"{2.0 ** (exponent - 1.0):.2f} per doubling vs linear")


if __name__ == "__main__":
    main()
