"""Running a validation scene: time steps for each solver, dynamics, and settling to rest."""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
import warp as wp

from ..collision import CollisionSettings
from ..errors import SimulationUnstable
from ..model import Model, State
from ..solvers.explicit.solver import critical_time_step
from ..solvers.select import DEFAULT_DT, make_solver

BODY_ONLY = CollisionSettings(cloth=False)
"""Collision against bodies only: the single-layer cases never fold onto themselves."""


def dynamics_time_step(model: Model, solver: str, resolve_period: float | None = None) -> float:
    """The step [s] a case integrates with: the solver's default, no more than 0.9 of the
    explicit stability limit for the explicit solver, and for the implicit one no more than
    1/200 of ``resolve_period`` [s] where the case measures a motion of that period (backward
    Euler's period error is then (2 pi / 200)^2 / 3, about 0.03 %)."""
    dt = DEFAULT_DT[solver]
    if solver == "explicit":
        return min(dt, 0.9 * critical_time_step(model))
    if resolve_period is not None:
        dt = min(dt, resolve_period / 200.0)
    return dt


def run(model: Model, solver: str, seconds: float, *, dt: float | None = None,
        collision: CollisionSettings | None = BODY_ONLY, observe: Callable[[State], None] | None = None,
        resolve_period: float | None = None) -> State:
    """Integrate ``model`` from its set-up state for ``seconds`` [s], calling ``observe(state)``
    after every step; returns the final state."""
    dt = dt or dynamics_time_step(model, solver, resolve_period)
    stepper = make_solver(solver, model, collision=collision)
    state, scratch = model.state(), model.state()
    control = model.control()
    for _ in range(int(round(seconds / dt))):
        stepper.step(state, scratch, control, dt)
        state, scratch = scratch, state
        if observe is not None:
            observe(state)
    return state


@wp.kernel
def _drag(v: wp.array(dtype=wp.vec3), keep: float):
    i = wp.tid()
    v[i] = v[i] * keep


def settle(model: Model, solver: str, *, collision: CollisionSettings | None = BODY_ONLY,
           rest_speed: float = 1e-5, memory: float = 0.05, check_every: float = 0.05,
           max_seconds: float | None = None, state: State | None = None,
           steady: Callable[[np.ndarray, np.ndarray], bool] | None = None) -> tuple[State, int]:
    """Bring ``model`` to static equilibrium and return the rest state and the steps taken.
    Raises :class:`SimulationUnstable` on blow-up and when ``max_seconds`` of simulated time
    pass first (default 30 s for the explicit solver; 300 s for the implicit one, whose
    sweeps, cut short in finely meshed stiff cloth, let the last millimetres creep in over
    tens of seconds, so it must also creep five times slower than ``rest_speed`` to be at
    rest).

    Damped dynamics (dynamic relaxation): the solver's own steps, each followed by a uniform
    drag that keeps exp(-dt / ``memory``) of the velocity (``memory`` [s], so both solvers
    damp alike whatever their step; 0.05 s damps the slow swing of a strip or a skirt near
    critically). The model is at rest when, over two checks ``check_every`` [s] apart, no
    node moved faster than ``rest_speed`` [m/s] on average. (The net force on a node is no
    criterion: in stiff cloth the round-off of single-precision positions already leaves a
    few percent of a small node's weight. Kinetic damping, which stops each node where its
    velocity turns, was tried and let a finely meshed strip jitter at its speed cap.) Where the
    case measures one quantity, ``steady(before, after)`` may judge two checks' positions [m]
    as well: the model is then also at rest when that quantity has stopped changing, as a
    laboratory reads a drape once its shadow is steady, though a limp cloth's folds may go on
    creeping for minutes."""
    dt = dynamics_time_step(model, solver)
    stepper = make_solver(solver, model, collision=collision)
    keep = math.exp(-dt / memory)
    state = state or model.state()
    scratch = model.state()
    control = model.control()
    window = max(int(round(check_every / dt)), 1)
    last = state.positions()
    quiet = 0
    max_seconds = max_seconds or (30.0 if solver == "explicit" else 300.0)
    if solver == "implicit":
        rest_speed *= 0.2  # its last millimetres creep in slowly: ask for a slower creep
    steps = int(max_seconds / dt)
    for it in range(1, steps + 1):
        stepper.step(state, scratch, control, dt)
        state, scratch = scratch, state
        wp.launch(_drag, dim=model.node_count, inputs=[state.node_qd, keep], device=model.device)
        if it % window == 0:
            points = state.positions()
            if not np.all(np.isfinite(points)):
                raise SimulationUnstable(f"the {solver} solver blew up while settling (non-finite positions)")
            speed = float(np.max(np.linalg.norm(points - last, axis=1))) / (window * dt)
            still = speed < rest_speed or (steady is not None and steady(last, points))
            last = points
            quiet = quiet + 1 if still else 0
            if quiet >= 2:
                return state, it
    raise SimulationUnstable(f"the {solver} solver did not come to rest in {max_seconds} s")
