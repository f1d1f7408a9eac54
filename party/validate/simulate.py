"""Running a validation scene: time steps for each solver, dynamics, and settling to rest."""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..collision import CollisionSettings
from ..collision.presets import BODY_ONLY
from ..errors import SimulationUnstable
from ..model import Model, State
from ..solvers.registry import make_solver, solver_class
from ..solvers.settle import SettleSettings
from ..solvers.settle import settle as settle_model

STEADY_WINDOW = 0.5
"""Time [s] between the checks of :func:`settle_until_unchanged`."""


def run(model: Model, solver: str, seconds: float, *, dt: float | None = None,
        collision: CollisionSettings | None = BODY_ONLY, observe: Callable[[State], None] | None = None,
        resolve_period: float | None = None) -> State:
    """Integrate ``model`` from its set-up state for ``seconds`` [s], calling ``observe(state)``
    after every step; returns the final state."""
    dt = dt or solver_class(solver).dynamics_step(model, resolve_period)
    stepper = make_solver(solver, model, collision=collision)
    state, scratch = model.state(), model.state()
    control = model.control()
    for _ in range(int(round(seconds / dt))):
        stepper.step(state, scratch, control, dt)
        state, scratch = scratch, state
        if observe is not None:
            observe(state)
    return state


def settle(model: Model, solver: str, *, collision: CollisionSettings | None = BODY_ONLY, **options) -> tuple[State, int]:
    """:func:`party.solvers.settle.settle` (body collision only unless told; ``options``: the
    other fields of :class:`~party.solvers.settle.SettleSettings`), which must come to rest:
    raises :class:`SimulationUnstable` when it does not. Returns the rest state and the steps
    taken."""
    settled = settle_model(model, solver, SettleSettings(collision=collision, **options))
    if not settled.at_rest:
        raise SimulationUnstable(f"the {solver} solver did not come to rest in {settled.seconds:g} s")
    return settled.state, settled.steps


def settle_until_unchanged(model: Model, solver: str, quantity: Callable[[np.ndarray], float], change: float,
                           **options) -> State:
    """:func:`settle`, also at rest once ``quantity(positions)`` (what the case measures) has
    changed by less than ``change`` over each of two :data:`STEADY_WINDOW`, though nodes still
    move: at 1/300 s the implicit solver's single-precision round-off keeps lightly held nodes
    wandering by micrometres (a 1 cm catenary chain by 3 um between checks 0.05 s apart,
    2e-5 to 5e-5 m/s, whatever the sweeps), above any speed that says rest, and a speed
    criterion is then met by chance or not at all. Returns the rest state."""

    def steady(before: np.ndarray, after: np.ndarray) -> bool:
        return abs(quantity(after) - quantity(before)) < change

    return settle(model, solver, steady=steady, check_every=STEADY_WINDOW, **options)[0]
