"""What every solver is: the contract the runner, the relaxations and the validation step through.

A solver advances a State over a Model (after Newton's ``solver.step``): it reads ``state_in``
and the model, writes ``state_out`` (a distinct State of the same model; the caller swaps the
two), and changes nothing else a caller can see but its own memory from step to step (which it
names for checkpoints: :mod:`party.solvers.memory`).
"""

from __future__ import annotations

from typing import ClassVar, Protocol, runtime_checkable

from ..model import Control, Model, State


@runtime_checkable
class Solver(Protocol):
    """A time stepper.

    Attributes:
        name: Its name on the command line (``--solver``).
        default_dt: The step [s] it takes unless told otherwise.
        settle_seconds: Longest simulated time [s] a settling (:func:`~party.solvers.settle.settle`)
            gives it to come to rest.
        creep: The rest speed a settling asks of it, as a share of the one asked of a solver
            that converges fully each step (1: the explicit solver's).
        model: The model it advances.
    """

    name: ClassVar[str]
    default_dt: ClassVar[float]
    settle_seconds: ClassVar[float]
    creep: ClassVar[float]
    model: Model

    def step(self, state_in: State, state_out: State, control: Control, dt: float) -> None:
        """Advance ``state_in`` by ``dt`` [s] into ``state_out``."""

    def stable_time_step(self) -> float:
        """The largest step [s] it stays stable at on its model (``math.inf``: any)."""

    def flush(self, state: State) -> None:
        """Finish work a run's last steps left pending (a crossing check the guard's interval
        had not reached), so that ``state`` may be written or measured."""

    @classmethod
    def configured(cls, model: Model, **options) -> "Solver":
        """The solver as party's scenes use it (see :func:`party.solvers.registry.make_solver`)."""

    @classmethod
    def relaxation_step(cls, model: Model) -> float:
        """The pseudo time step [s] of a static relaxation of ``model`` with this solver."""

    @classmethod
    def dynamics_step(cls, model: Model, resolve_period: float | None = None) -> float:
        """The step [s] to integrate ``model``'s dynamics with, resolving motions of
        ``resolve_period`` [s] where one is given."""
