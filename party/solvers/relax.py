"""Static relaxation: the paper's "iterate ignoring inertia until the total (mostly spring)
energy settles" (section 7, figure 12).

Each iteration is one explicit step (eqs. 3-5, collisions and plastic limit included; or one
implicit step, :mod:`party.solvers.implicit`, which allows a far larger dt) whose
velocities v* are capped at ``max_speed`` before positions move, so no node moves more than
``max_speed * dt`` per iteration. With ``momentum`` 0 every velocity is then zeroed: the paper's
iteration without inertia, a gradient descent. With ``momentum`` m > 0 a fraction m of v* is
kept and a node whose velocity turned against the one it had (it has passed a minimum of the
energy along its path) is stopped there: dynamic relaxation with kinetic damping (Day 1965),
the standard energy descent of form finding, which reaches the same static equilibrium in
fewer iterations.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..collision import CollisionSettings
from ..model import Control, Model, State
from .registry import make_solver


KINETIC_MOMENTUM = 0.9
"""Velocity kept per iteration by the sewing's kinetic-damping relaxation: at the explicit
solver's small steps a sleeve falls 2 cm/s at most, so sleeves sewn out sideways stay out, as in
the paper's figure 12 (the drape keeps more, :class:`party.garment.draping.KineticDrape`)."""


def total_energy(model: Model, points: np.ndarray) -> float:
    """Spring energy sum 1/2 e (|r_k - r_i| - l0)^2 plus the free nodes' potential energy in
    gravity [J]; kinetic energy is left out (it is what relaxation removes)."""
    h = model.host
    e = h.elements
    length = np.linalg.norm(points[e[:, 1]] - points[e[:, 0]], axis=1)
    spring = 0.5 * float(np.sum(h.element_stiffness * (length - h.element_rest_length) ** 2))
    g = np.array([model.gravity[0], model.gravity[1], model.gravity[2]], float)
    free = ~h.kinematic
    return spring - float(np.sum(h.mass[free] * (points[free] @ g)))


@dataclass
class RelaxResult:
    """How a relaxation went: ``iterations`` run, ``energy`` logged as (iteration, J) pairs,
    and whether the energy ``converged`` before ``max_iterations``."""

    iterations: int = 0
    energy: list = field(default_factory=list)
    converged: bool = False

    @property
    def final_energy(self) -> float:
        return self.energy[-1][1] if self.energy else float("nan")

    def copy(self) -> "RelaxResult":
        """This log as it is now, to keep while this one goes on."""
        return RelaxResult(self.iterations, list(self.energy), self.converged)

    def extend(self, more: "RelaxResult") -> None:
        """Add relaxation ``more``, run on from where this one stopped: its iterations counted
        on from this one's, its outcome the latest."""
        self.energy += [(self.iterations + it, e) for it, e in more.energy]
        self.iterations += more.iterations
        self.converged = more.converged


class StaticRelaxation:
    """The paper's iteration ignoring inertia: a model iterated towards static equilibrium (see
    the module docstring); not a time stepper, though each iteration is a solver's step.

    Args:
        model: The model; its gravity is used as is (zero for sewing, on for draping).
        collision: Collision settings; collisions stay on throughout by default.
        max_speed: Cap on node speed [m/s] during relaxation.
        momentum: Fraction of velocity kept per iteration (0: velocities zeroed, the paper's
            iteration without inertia).
        solver: The solver whose steps it iterates (see :mod:`party.solvers.registry`): the
            explicit one's (dt below its stability limit) or the implicit one's (any dt).
    """

    def __init__(self, model: Model, *, collision: CollisionSettings | None = CollisionSettings(),
                 max_speed: float = 1.0, momentum: float = 0.0, solver: str = "explicit") -> None:
        self.model = model
        self.momentum = float(momentum)
        damping = (max_speed, 1.0 if momentum == 0.0 else momentum)
        self.stepper = make_solver(solver, model, collision=collision, kinetic_damping=damping, static=True)

    def iterate(self, state: State, scratch: State, control: Control, dt: float) -> None:
        """One iteration from ``state`` into ``scratch`` (swap after)."""
        self.stepper.step(state, scratch, control, dt)
        if self.momentum == 0.0:
            scratch.node_qd.zero_()

    def relax(self, state: State, dt: float, *, max_iterations: int = 20000, min_iterations: int = 200,
              log_every: int = 50, tolerance: float = 2e-3, window: int = 6, on_log=None,
              resumed: RelaxResult | None = None, should_stop: Callable[[], bool] | None = None) -> RelaxResult:
        """Iterate ``state`` in place until the energy changes by less than ``tolerance`` (relative)
        over ``window`` logs, or ``max_iterations``. ``on_log(iteration, energy, state)`` is called
        at each log (for progress bars and partial output). ``resumed``: the log of this
        relaxation until it stopped, ``state`` holding where it was; it goes on from there.
        ``should_stop()``, asked at each log, ends it there (not converged) when true."""
        control = self.model.control()
        scratch = self.model.state()
        result = RelaxResult(resumed.iterations, list(resumed.energy)) if resumed else RelaxResult()
        current = state
        it = result.iterations
        for it in range(result.iterations + 1, max_iterations + 1):
            self.iterate(current, scratch, control, dt)
            current, scratch = scratch, current
            if it % log_every == 0 or it == max_iterations:
                energy = total_energy(self.model, current.positions())
                result.energy.append((it, energy))
                if on_log is not None:
                    on_log(it, energy, current)
                if not np.isfinite(energy) or (should_stop is not None and should_stop()):
                    break
                if it >= min_iterations and len(result.energy) > window:
                    old = result.energy[-1 - window][1]
                    scale = max(abs(old), abs(energy), 1e-12)
                    if abs(old - energy) <= tolerance * scale:
                        result.converged = True
                        break
        result.iterations = it
        self.stepper.flush(current)
        if current is not state:
            state.assign(current)
        return result
