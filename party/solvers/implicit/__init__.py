from .solver import SolverImplicit

__all__ = ["SolverImplicit"]
