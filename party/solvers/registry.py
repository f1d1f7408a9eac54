"""The solvers by name (``--solver``): the one place a solver is chosen."""

from __future__ import annotations

from ..errors import InvalidInput
from ..model import Model
from .explicit import SolverExplicit
from .implicit import SolverImplicit
from .solver import Solver

SOLVERS: dict[str, type[Solver]] = {cls.name: cls for cls in (SolverExplicit, SolverImplicit)}
"""explicit: the paper's integrator (eqs. 3-5), the faithful reference; implicit: backward
Euler by Vertex Block Descent, for large steps."""


def solver_class(name: str) -> type[Solver]:
    """The solver called ``name``; :class:`InvalidInput` naming the known ones otherwise."""
    if name not in SOLVERS:
        raise InvalidInput(f"unknown solver {name!r}; known: {', '.join(SOLVERS)}")
    return SOLVERS[name]


def check_solver(name: str) -> str:
    """``name`` where it names a solver (see :func:`solver_class`)."""
    solver_class(name)
    return name


def make_solver(name: str, model: Model, **options) -> Solver:
    """The solver ``name`` for ``model`` as party's scenes use it (its ``configured``):
    ``collision`` (settings, or None for none), ``air``, and ``static`` for runs that seek only
    a rest shape; ``kinetic_damping`` for static relaxation; ``iterations`` and
    ``contact_rounds`` for the implicit solver only."""
    return solver_class(name).configured(model, **options)
