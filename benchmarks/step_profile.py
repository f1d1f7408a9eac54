"""Where a step's time goes: wall time per kernel of party's steps, in three workloads.

    python benchmarks/step_profile.py sphere-drop [--grid 100] [--self-collision on|off] [--seconds 1]
                                             [--dt S] [--solver implicit|explicit]
    python benchmarks/step_profile.py square [--nodes 100000] [--steps 10] [--self-collision on|off]
    python benchmarks/step_profile.py drape [--garment reference|flare] [--solver implicit|explicit]
                                       [--spacing-mm 20]

``sphere-drop`` is ``party run sphere-drop`` without output; ``square`` is the cloth of
``benchmarks/scaling.py`` (a 1 m square resting on the sphere) at one size; ``drape`` drapes
the reference dress on dress form M, or GarmentCode's ``dress_sleeves_flare`` on ``mean_all.obj``
(from ``../shared/``), in wool flannel at 20 mm (or ``--spacing-mm``), as ``benchmarks/compare.py``
does, and splits its time into sewing and draping.

Prints the steps' wall milliseconds per step, and per kernel its milliseconds per step,
launches per step and share of the steps' time, largest first; ``drape`` with the implicit
solver also, check by check, how far the nodes moved since the last check (mean and 99th
percentile) and on how many steps the crossing guard sent how many nodes back meanwhile.
Every launch that party makes through :mod:`party.launch` is timed (a CPU launch returns when
its kernel has run) and the implicit solve replayed as a recorded graph counts as one entry;
the rest of a step (host work between launches) is the last line. The sphere drop and the
square leave out their first steps (compilation, the first search). Timing every launch costs
a few percent. For the implicit solver it also prints how often its worker threads gave their
core away while waiting for each other (``SolverImplicit.worker_yields``): at 64 x 64 some 160
times a step alone, some 1,500 beside one busy process, whose core the sweeps then share. Run
it as a script (it imports ``scaling.py`` and ``compare.py`` from beside it), on an otherwise
idle machine.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections import Counter
from contextlib import contextmanager
from typing import Callable, Iterator

os.environ["PARTY_DEVICE"] = "cpu"  # a CUDA launch returns before its kernel has run: only the CPU is timed

import warp as wp  # noqa: E402

import party.launch  # noqa: E402
from party.scenes import sphere_drop  # noqa: E402
from party.solvers.implicit import SolverImplicit  # noqa: E402

WARM_UP_STEPS = 3
GRAPH = "(implicit solve, replayed graph)"
LAUNCHERS = ("launch", "launch_items", "launch_workers")


class KernelClock:
    """Wall seconds and launches per kernel while :meth:`running` (host-synchronous CPU
    launches; on CUDA a launch only queues its kernel, so use this on the CPU)."""

    def __init__(self) -> None:
        self.seconds: Counter[str] = Counter()
        self.launches: Counter[str] = Counter()
        self.on = False

    def _timed(self, run: Callable, name: Callable) -> Callable:
        def timed(*args, **kwargs):
            if not self.on:
                return run(*args, **kwargs)
            started = time.perf_counter()
            try:
                return run(*args, **kwargs)
            finally:
                key = name(args)
                self.seconds[key] += time.perf_counter() - started
                self.launches[key] += 1
        return timed

    @contextmanager
    def installed(self) -> Iterator["KernelClock"]:
        """Route party's launches (the names its modules imported from :mod:`party.launch`) and
        Warp's graph replays through the clock; restored on exit."""
        swapped = []
        for launcher in LAUNCHERS:
            original = getattr(party.launch, launcher)
            timed = self._timed(original, _kernel_name)
            for name, module in list(sys.modules.items()):
                if (name.startswith("party.") and module is not party.launch
                        and getattr(module, launcher, None) is original):
                    swapped.append((module, launcher, original))
                    setattr(module, launcher, timed)
        swapped.append((wp, "capture_launch", wp.capture_launch))
        wp.capture_launch = self._timed(wp.capture_launch, lambda args: GRAPH)
        try:
            yield self
        finally:
            for module, name, original in reversed(swapped):
                setattr(module, name, original)

    @contextmanager
    def running(self) -> Iterator[None]:
        self.on = True
        try:
            yield
        finally:
            self.on = False

    def report(self, wall: float, steps: int) -> None:
        """Print the kernels' share of ``wall`` [s] over ``steps`` steps."""
        print(f"{steps} steps, {1000.0 * wall / steps:.2f} ms a step")
        print(f"{'ms/step':>9} {'launches/step':>14} {'share':>6}  kernel")
        for key, seconds in self.seconds.most_common():
            print(f"{1000.0 * seconds / steps:9.3f} {self.launches[key] / steps:14.2f} {seconds / wall:6.1%}  {key}")
        host = wall - sum(self.seconds.values())
        print(f"{1000.0 * host / steps:9.3f} {'':>14} {host / wall:6.1%}  (host, between launches)")


def _kernel_name(args: tuple) -> str:
    """The kernel of a launch's arguments (the first)."""
    return getattr(args[0], "key", str(args[0]))


def run_steps(model, solver, dt: float, steps: int, clock: KernelClock) -> None:
    """``steps`` steps of ``solver`` from ``model``'s initial state after the warm-up, timed."""
    state, scratch, control = model.state(), model.state(), model.control()
    for _ in range(WARM_UP_STEPS):
        solver.step(state, scratch, control, dt)
        state, scratch = scratch, state
    yields = solver.worker_yields() if isinstance(solver, SolverImplicit) else 0
    with clock.installed(), clock.running():
        started = time.perf_counter()
        for _ in range(steps):
            solver.step(state, scratch, control, dt)
            state, scratch = scratch, state
        wall = time.perf_counter() - started
    describe(solver, dt, steps, yields)
    clock.report(wall, steps)


def describe(solver, dt: float, steps: int, yields_before: int) -> None:
    """Print the implicit solver's sweeps, colours and worker threads for steps of ``dt`` [s],
    and how often a worker gave its core away in ``steps`` steps (the count was
    ``yields_before`` before them)."""
    if isinstance(solver, SolverImplicit):
        yields = (solver.worker_yields() - yields_before) / steps
        print(f"implicit solver: {solver.sweeps(dt)} sweeps a step of {dt:.6g} s over {len(solver.color_offsets) - 1} "
              f"colours, {solver.workers} worker thread(s), which gave their core away {yields:.1f} times a step "
              "while waiting for each other")


def profile_sphere_drop(args: argparse.Namespace) -> None:
    scene = sphere_drop.build(sphere_drop.Settings(grid=args.grid, self_collision=args.self_collision == "on",
                                                   solver=args.solver, duration=args.seconds, dt=args.dt))
    steps = max(1, round(scene.duration / scene.dt) - WARM_UP_STEPS)
    print(f"sphere drop, {args.grid}x{args.grid} nodes, self-collision {args.self_collision}, {args.solver} solver")
    run_steps(scene.model, scene.solver, scene.dt, steps, KernelClock())


def profile_square(args: argparse.Namespace) -> None:
    from scaling import square_on_sphere

    model, solver, dt = square_on_sphere(args.nodes, args.self_collision == "on")
    print(f"1 m square on the sphere, {model.node_count} nodes, self-collision {args.self_collision}")
    run_steps(model, solver, dt, args.steps, KernelClock())
    overflow = solver.collision.candidate_overflow() if solver.collision is not None else 0
    print(f"candidates dropped for want of room: {overflow}")


def profile_drape(args: argparse.Namespace) -> None:
    from dataclasses import asdict

    from compare import garment_scenes, run_drape
    from party.garment import draping

    scenes = {label.split()[0].lower(): (label.rsplit(", ", 1)[0], pattern, body)
              for label, pattern, body, _ in garment_scenes()}
    key = "garmentcode" if args.garment == "flare" else "reference"
    if key not in scenes:
        raise SystemExit("GarmentCode's flare dress is not in ../shared/data/garmentcode/")
    name, pattern, body = scenes[key]
    label, spacing = f"{name}, {args.spacing_mm:g} mm", args.spacing_mm / 1000
    clock = KernelClock()
    wall = {}
    guard = GuardLog()
    rows: list[tuple[float, float]] = []
    method = draping.DRAPING[args.solver]

    class Profiled(type(method)):
        """The solver's drape, its steps timed kernel by kernel and its shape checks logged."""

        def run(self, *a, **k):
            guard.reset()  # the sewing's reverts are not the drape's
            started = time.perf_counter()
            with clock.running():
                try:
                    return super().run(*a, **k)
                finally:
                    wall["draping"] = time.perf_counter() - started

        def steady(self, before, after):
            import numpy as np

            moved = 1000.0 * np.linalg.norm(after - before, axis=1)
            rows.append((float(moved.mean()), float(np.percentile(moved, 99))))
            guard.close()
            return super().steady(before, after)

    draping.DRAPING[args.solver] = Profiled(**asdict(method))
    try:
        with clock.installed(), guard.installed():
            row = run_drape(pattern, body, args.solver, spacing)
    finally:
        draping.DRAPING[args.solver] = method
    print(f"{label}, {row['nodes']} nodes, {args.solver} solver: {row['wall_seconds_to_rest']:.1f} s in all, "
          f"draping {wall['draping']:.1f} s (the rest is sewing, set-up and output); at rest {row['at_rest']}, "
          f"{row['body_penetrations']} penetrations, {row['cloth_crossings']} crossings, "
          f"{row['body_vertices_through_cloth']} body vertices through the cloth")
    print("draping steps:")
    clock.report(wall["draping"], max(row["draping_steps"], 1))
    if rows:
        print("draping, check by check (nodes' motion since the last check; the crossing guard's reverts):")
        print(f"{'check':>5} {'mean mm':>8} {'p99 mm':>7} {'steps reverting':>16} {'nodes reverted':>15}")
        for k, ((mean, p99), (steps, nodes)) in enumerate(zip(rows, guard.windows), start=1):
            print(f"{k:5d} {mean:8.2f} {p99:7.2f} {steps:16d} {nodes:15d}")


class GuardLog:
    """The crossing guard's reverts during a drape, window by window between the drape's checks:
    (steps with a revert, nodes reverted) in ``windows``, a window closed by :meth:`close`."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self.windows: list[tuple[int, int]] = []
        self._steps = self._nodes = 0

    def close(self) -> None:
        self.windows.append((self._steps, self._nodes))
        self._steps = self._nodes = 0

    @contextmanager
    def installed(self) -> Iterator["GuardLog"]:
        from party.collision.crossing_guard import CrossingGuard

        original = CrossingGuard.check

        def check(guard, x, v):
            count = original(guard, x, v)
            self._steps += int(count > 0)
            self._nodes += count
            return count

        CrossingGuard.check = check
        try:
            yield self
        finally:
            CrossingGuard.check = original


def main() -> None:
    from compare import GARMENT_SPACING_MM

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    workloads = parser.add_subparsers(dest="workload", required=True)
    drop = workloads.add_parser("sphere-drop", help="party run sphere-drop's steps")
    drop.add_argument("--grid", type=int, default=100)
    drop.add_argument("--self-collision", choices=("on", "off"), default="on")
    drop.add_argument("--seconds", type=float, default=1.0)
    drop.add_argument("--dt", type=float, default=None, help="time step [s] (default: the solver's)")
    drop.add_argument("--solver", choices=("implicit", "explicit"), default="implicit")
    square = workloads.add_parser("square", help="benchmarks/scaling.py's square at one size")
    square.add_argument("--nodes", type=int, default=100_000)
    square.add_argument("--steps", type=int, default=10)
    square.add_argument("--self-collision", choices=("on", "off"), default="on")
    drape = workloads.add_parser("drape", help="a garment draped to rest, as benchmarks/compare.py does")
    drape.add_argument("--garment", choices=("reference", "flare"), default="reference")
    drape.add_argument("--solver", choices=("implicit", "explicit"), default="implicit")
    drape.add_argument("--spacing-mm", type=float, default=GARMENT_SPACING_MM, help="the net's node spacing [mm]")
    args = parser.parse_args()
    if getattr(args, "steps", 1) < 1 or getattr(args, "seconds", 1.0) <= 0 or getattr(args, "spacing_mm", 1.0) <= 0:
        parser.error("--steps, --seconds and --spacing-mm must be positive")
    {"sphere-drop": profile_sphere_drop, "square": profile_square, "drape": profile_drape}[args.workload](args)


if __name__ == "__main__":
    main()
