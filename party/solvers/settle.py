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
from .registry import make_solver, solver_class

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

DRAPE_SWEEPS = 15
"""The implicit solver's sweeps per step when cloth drapes to rest (garments, Cusick
specimens), half as many again as its default: a solve cut short leaves the soft modes of
hanging folds drifting, each step starting them a little off their equilibrium, and cloth held
out by its own stiffness crumples (a denim Cusick specimen does at 10 sweeps, where
:data:`~party.solvers.implicit.solver.STIFFNESS_PER_SWEEP` alone would allow them). At 15 the
drape no longer changes with more sweeps, and garments come to rest in a few seconds of
draping."""

@dataclass
class Settled:
    """The outcome of :func:`settle`: the last ``state``, the ``steps`` taken, the simulated
    ``seconds``, and whether the model came to rest (``at_rest``) before the time limit."""

    state: State
    steps: int
    seconds: float
    at_rest: bool


@wp.kernel
def _drag(v: wp.array(dtype=wp.vec3), keep: float, max_speed: float):
    i = wp.tid()
    vi = v[i] * keep
    speed = wp.length(vi)
    if speed > max_speed:
        vi = vi * (max_speed / speed)
    v[i] = vi


@dataclass(frozen=True)
class SettleSettings:
    """How :func:`settle` brings a model to rest.

    Attributes:
        collision: Collision settings (None: none).
        rest_speed: The model is at rest when, over two checks ``check_every`` [s] apart, no
            node moved faster than this [m/s] on average (times the solver's ``creep``). The
            net force on a node is no criterion: in stiff cloth the round-off of
            single-precision positions already leaves a few percent of a small node's weight.
        memory: Each step is followed by a uniform drag that keeps exp(-dt / ``memory``) of the
            velocity [s], so that both solvers damp alike whatever their step; 0.05 s damps the
            slow swing of a strip or a skirt near critically.
        check_every: Simulated time between checks [s].
        max_seconds: Most simulated time [s] (None: the solver's ``settle_seconds``).
        steady: ``steady(before, after)`` judges two checks' positions [m] as well: the model
            is then also at rest when it says the quantity a case measures, or the shape, has
            stopped changing, though single nodes may go on creeping or jittering.
        dt: The step [s] (None: the solver's ``dynamics_step``).
        max_speed: Speed cap [m/s] applied with the drag.
        iterations: The implicit solver's sweeps per step (None: its default).
    """

    collision: CollisionSettings | None = CollisionSettings()
    rest_speed: float = 1e-5
    memory: float = 0.05
    check_every: float = 0.05
    max_seconds: float | None = None
    steady: Callable[[np.ndarray, np.ndarray], bool] | None = None
    dt: float | None = None
    max_speed: float = math.inf
    iterations: int | None = None


def settle(model: Model, solver: str, settings: SettleSettings = SettleSettings(), *, state: State | None = None,
           on_check: Callable[[int, State], None] | None = None, first_step: int = 0,
           should_stop: Callable[[], bool] | None = None) -> Settled:
    """Bring ``model`` to static equilibrium from ``state`` (default: its set-up state) with the
    solver called ``solver``, as ``settings`` say. Raises :class:`SimulationUnstable` on
    blow-up; returns with ``at_rest`` False when its time is up first. ``on_check(step,
    state)`` is called at every check (progress, logs). ``first_step`` > 0 resumes a settling
    that stopped after that many steps, ``state`` then holding where it was (the solver's own
    memory starts afresh); the time limit counts them. The solver runs as for a static run
    (``static``: the implicit one takes no contact re-solves, a settling being judged by its
    rest shape). ``should_stop()``, asked at every check, ends it there (not at rest) when true."""
    collision, rest_speed, memory = settings.collision, settings.rest_speed, settings.memory
    check_every, max_seconds, steady = settings.check_every, settings.max_seconds, settings.steady
    dt, max_speed, iterations = settings.dt, settings.max_speed, settings.iterations
    kind = solver_class(solver)
    dt = dt or kind.dynamics_step(model)
    stepper = make_solver(solver, model, collision=collision, iterations=iterations, static=True)
    keep = math.exp(-dt / memory)
    state = state or model.state()
    scratch = model.state()
    control = model.control()
    window = max(int(round(check_every / dt)), 1)
    last = state.positions()
    quiet = 0
    max_seconds = max_seconds or kind.settle_seconds
    rest_speed *= kind.creep
    steps = int(max_seconds / dt)
    for it in range(first_step + 1, steps + 1):
        stepper.step(state, scratch, control, dt)
        state, scratch = scratch, state
        launch(_drag, dim=model.node_count, inputs=[state.node_qd, keep, float(max_speed)], device=model.device)
        if it % window == 0:
            stepper.flush(state)
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
            if should_stop is not None and should_stop():
                return Settled(state, it, it * dt, False)
    return Settled(state, steps, steps * dt, False)
