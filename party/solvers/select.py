"""Choosing a solver by name (the ``--solver`` option)."""

from __future__ import annotations

from dataclasses import replace

from ..collision import CollisionSettings
from ..errors import InvalidInput
from ..model import Model
from .aero import Air
from .explicit import SolverExplicit
from .implicit import SolverImplicit

SOLVERS = ("explicit", "implicit")
"""explicit: the paper's integrator (eqs. 3-5), the faithful reference; implicit: backward
Euler by Vertex Block Descent, for large steps."""

DEFAULT_DT = {"explicit": 1.0e-4, "implicit": 1.0 / 300.0}
"""Default time step [s]: the paper's for the explicit solver; a 60 Hz frame in 5 substeps for
the implicit one."""


def guard_every(dt: float) -> int:
    """Steps of ``dt`` [s] between crossing-guard checks: one check per implicit step's worth of
    time (:data:`DEFAULT_DT`), so that the explicit solver's small steps pay for a check every
    few dozen steps rather than every step, and a reverted node goes back at most 1/300 s."""
    return max(1, int(DEFAULT_DT["implicit"] / dt * (1.0 + 1e-9)))


def large_step_collision(collision: CollisionSettings | None) -> CollisionSettings | None:
    """``collision`` for the implicit solver's large steps: with the crossing guard on, since
    they let more edges slip through each other, cloth triangles answering body vertices
    (:mod:`party.collision.body_vertices`), whose pushes the guard keeps from crossing layers,
    and nodes stopped at the body moved onto its shell (``arrive``), not left a step's approach
    off it. The explicit solver keeps the paper's Collision() as printed."""
    return None if collision is None else replace(collision, crossing_guard=True, body_vertices=True, arrive=True)


def check_solver(name: str) -> str:
    if name not in SOLVERS:
        raise InvalidInput(f"unknown solver {name!r}; known: {', '.join(SOLVERS)}")
    return name


def make_solver(name: str, model: Model, *, collision: CollisionSettings | None = CollisionSettings(),
                air: Air | None = None, iterations: int | None = None, contact_rounds: int | None = None):
    """The solver ``name`` (see :data:`SOLVERS`) for ``model``: the explicit one with the
    paper's Collision(), the implicit one with :func:`large_step_collision`. ``iterations``:
    the implicit solver's sweeps per step, ``contact_rounds`` its contact re-solves (None:
    its defaults)."""
    implicit_only = {"iterations": iterations, "contact_rounds": contact_rounds}
    given = {key: value for key, value in implicit_only.items() if value is not None}
    if check_solver(name) == "explicit":
        if given:
            raise InvalidInput(f"{', '.join(given)} apply to the implicit solver only")
        return SolverExplicit(model, collision=collision, air=air)
    return SolverImplicit(model, collision=large_step_collision(collision), air=air, **given)
