"""Static equilibrium by damped dynamics (dynamic relaxation): the solver's own steps, each
followed by a uniform drag, until the cloth stops moving."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
import warp as wp

from ..collision import CollisionSettings
from ..errors import SimulationUnstable
from ..launch import launch
from ..model import Model, State
from .explicit.solver import critical_time_step
from .select import DEFAULT_DT, make_solver

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

DRAPE_SWEEPS = 15
"""The implicit solver's sweeps per step when cloth drapes to rest (garments, Cusick
specimens), half as many again as its default: a solve cut short leaves the soft modes of
hanging folds drifting, each step starting them a little off their equilibrium, and cloth held
out by its own stiffness crumples. GarmentCode's flare dress on mean_all came to rest after
10 s of draping at 30 mm and was still moving after 10 s at 20 mm with 10 sweeps, after 7 s and
8.5 s with 15 (and after 5 s at 30 mm with 20). A denim Cusick specimen at 7.5 mm and 1/1,000 s
(K dt^2 / m = 2,000, which :data:`~party.solvers.implicit.solver.STIFFNESS_PER_SWEEP` gives 10
sweeps) crumpled to DC 13.4 % with 3 folds at 10 sweeps and draped to 41.2, 40.3, 42.1 and
41.4 % with 9 folds at 15, 20, 25 and 40."""

MAX_SECONDS = {"explicit": 30.0, "implicit": 300.0}
"""Default limit on the simulated time [s] a settling may take (see :func:`settle`)."""


@dataclass
class Settled:
    """The outcome of :func:`settle`: the last ``state``, the ``steps`` taken, the simulated
    ``seconds``, and whether the model came to rest (``at_rest``) before the time limit."""

    state: State
    steps: int
    seconds: float
    at_rest: bool


def dynamics_time_step(model: Model, solver: str, resolve_period: float | None = None) -> float:
    """The step [s] to integrate ``model`` with: the solver's default, no more than 0.9 of the
    explicit stability limit for the explicit solver, and for the implicit one no more than
    1/200 of ``resolve_period`` [s] where a motion of that period must be resolved (backward
    Euler's period error is then (2 pi / 200)^2 / 3, about 0.03 %)."""
    dt = DEFAULT_DT[solver]
    if solver == "explicit":
        return min(dt, 0.9 * critical_time_step(model))
    if resolve_period is not None:
        dt = min(dt, resolve_period / 200.0)
    return dt


@wp.kernel
def _drag(v: wp.array(dtype=wp.vec3), keep: float, max_speed: float):
    i = wp.tid()
    vi = v[i] * keep
    speed = wp.length(vi)
    if speed > max_speed:
        vi = vi * (max_speed / speed)
    v[i] = vi


def settle(model: Model, solver: str, *, collision: CollisionSettings | None = CollisionSettings(),
           rest_speed: float = 1e-5, memory: float = 0.05, check_every: float = 0.05,
           max_seconds: float | None = None, state: State | None = None,
           steady: Callable[[np.ndarray, np.ndarray], bool] | None = None,
           on_check: Callable[[int, State], None] | None = None, dt: float | None = None,
           max_speed: float = math.inf, iterations: int | None = None, first_step: int = 0) -> Settled:
    """Bring ``model`` to static equilibrium from ``state`` (default: its set-up state).
    Raises :class:`SimulationUnstable` on blow-up; returns with ``at_rest`` False when
    ``max_seconds`` of simulated time pass first (default :data:`MAX_SECONDS`: the implicit
    solver's sweeps, cut short in finely meshed stiff cloth, let the last millimetres creep in
    over tens of seconds, so it must also creep five times slower than ``rest_speed`` to be
    at rest).

    Each step of the solver is followed by a uniform drag that keeps exp(-dt / ``memory``) of
    the velocity (``memory`` [s]: both solvers damp alike whatever their step; 0.05 s damps the
    slow swing of a strip or a skirt near critically) and caps its speed at ``max_speed``
    [m/s]. The model is at rest when, over two checks ``check_every`` [s] apart, no node
    moved faster than ``rest_speed`` [m/s] on average. (The net force on a node is no criterion: in stiff cloth the round-off of
    single-precision positions already leaves a few percent of a small node's weight. Kinetic
    damping, which stops each node where its velocity turns, was tried and let a finely meshed
    strip jitter at its speed cap.) ``steady(before, after)`` may judge two checks' positions
    [m] as well: the model is then also at rest when that says the quantity a case measures,
    or the shape, has stopped changing, though single nodes may go on creeping or jittering.
    ``on_check(step, state)`` is called at every check (progress, logs). The step ``dt`` [s]
    is :func:`dynamics_time_step`'s unless given; ``iterations``, the implicit solver's sweeps
    per step, its default unless given. ``first_step`` > 0 resumes a settling that stopped
    after that many steps, ``state`` then holding where it was (the solver's own memory starts
    afresh); the time limit counts them. The implicit solver takes no contact re-solves here
    (``contact_rounds`` 0, :meth:`~party.solvers.implicit.SolverImplicit.resolve_contacts`):
    a settling is judged by its rest shape, and the plastic limit takes up a step's stretch
    over the steps after. (With them, case 7's fabric F draped with 8.33 folds on average
    instead of 7.67; the explicit solver gives 8.0, the drapemeter measured 7.)"""
    dt = dt or dynamics_time_step(model, solver)
    stepper = make_solver(solver, model, collision=collision, iterations=iterations,
                          contact_rounds=0 if solver == "implicit" else None)
    keep = math.exp(-dt / memory)
    state = state or model.state()
    scratch = model.state()
    control = model.control()
    window = max(int(round(check_every / dt)), 1)
    last = state.positions()
    quiet = 0
    max_seconds = max_seconds or MAX_SECONDS[solver]
    if solver == "implicit":
        rest_speed *= 0.2  # its last millimetres creep in slowly: ask for a slower creep
    steps = int(max_seconds / dt)
    for it in range(first_step + 1, steps + 1):
        stepper.step(state, scratch, control, dt)
        state, scratch = scratch, state
        launch(_drag, dim=model.node_count, inputs=[state.node_qd, keep, float(max_speed)], device=model.device)
        if it % window == 0:
            stepper.end.flush(state)
            points = state.positions()
            if not np.all(np.isfinite(points)):
                raise SimulationUnstable(f"the {solver} solver blew up while settling (non-finite positions)")
            if on_check is not None:
                on_check(it, state)
            speed = float(np.max(np.linalg.norm(points - last, axis=1))) / (window * dt)
            still = speed < rest_speed or (steady is not None and steady(last, points))
            last = points
            quiet = quiet + 1 if still else 0
            if quiet >= 2:
                return Settled(state, it, it * dt, True)
    return Settled(state, steps, steps * dt, False)
