from .solver import SolverExplicit

__all__ = ["SolverExplicit"]
