"""Solvers advance a State: ``solver.step(state_in, state_out, control, dt)``."""

from .aero import Air
from .explicit import SolverExplicit
from .implicit import SolverImplicit

__all__ = ["Air", "SolverExplicit", "SolverImplicit"]
