"""Draping a sewn garment: let it fall onto its body under gravity until it rests.

Each solver drapes its own way (:data:`DRAPING`, by the solver's name):

- the explicit solver by the paper's static relaxation (section 7: iterations with kinetic
  damping until the energy settles, :class:`KineticDrape`), as the sewing is relaxed;
- the implicit solver by damped dynamics (its own steps, each followed by a drag, until the
  garment's shape is steady, :class:`DampedDrape`): its energy jitters by a few percent from
  contact and plastic-limit corrections, so an energy criterion would stop it by chance while
  sleeves still fall.

Collisions stay on throughout, the crossing guard with them, and the cloth's triangles answer
the body's vertices (:mod:`party.collision.body_vertices`), so that no body vertex shows
through between the cloth's nodes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..collision import presets
from ..model import Model, State
from ..progress import relax_progress
from ..solvers.explicit import SolverExplicit
from ..solvers.implicit import SolverImplicit
from ..solvers.relax import RelaxResult, StaticRelaxation, total_energy
from ..solvers.settle import DRAPE_SWEEPS, SettleSettings, Settled, settle

Saver = Callable[[int, list, State], None]
"""``on_save(step, energy log [(step, J)], state)``: a drape's checkpoint, called at each check."""

Stop = Callable[[], bool]
"""``stop()``: true when the drape must stop where it is (its time limit passed)."""


@dataclass(frozen=True)
class KineticDrape:
    """The explicit solver's drape: the relaxation of :mod:`party.solvers.relax` (kinetic
    damping keeping ``momentum`` of the velocity, speeds capped at ``max_speed`` [m/s]) until
    the energy settles (to 0.2 % over 300 iterations, at least ``min_iterations``) or
    ``iterations``. The plastic limit is enforced again after contact: the body vertices' push
    on a tight hem would otherwise outrun it. The crossing guard also checks once when it stops.

    The sewing keeps less of the velocity (:data:`~party.solvers.relax.KINETIC_MOMENTUM`, a
    terminal speed of a few cm/s at the explicit steps) so that sewn panels stay where they are
    sewn; a drape must let a circle skirt sewn out flat fall half a metre to hang, which at
    that speed takes tens of thousands of iterations. Keeping 0.99 raises the terminal speed
    tenfold; nodes still stop where their velocity turns, and the speed cap keeps every
    iteration's move within the collision search."""

    iterations: int = 15000
    min_iterations: int = 300
    momentum: float = 0.99
    max_speed: float = 1.0

    def steps_planned(self) -> int:
        """The most iterations it takes."""
        return self.iterations

    def run(self, model: Model, state: State, first_step: int, energy: list[tuple[int, float]], on_save: Saver,
            progress: bool, stop: Stop | None = None) -> tuple[Settled, list[tuple[int, float]]]:
        """Drape ``model`` from ``state`` after ``first_step`` iterations that logged ``energy``
        [(iteration, J)]; ``on_save`` at every log, and there ``stop()`` may end it. Returns the
        outcome (``at_rest``: the energy settled) and the energy log."""
        dt = SolverExplicit.relaxation_step(model)
        with relax_progress("draping", self.iterations, progress) as on_log:
            logged = list(energy)

            def on_log_and_save(iteration: int, energy_now: float, state) -> None:
                on_log(iteration, energy_now, state)
                logged.append((iteration, energy_now))
                on_save(iteration, logged, state)

            relaxation = StaticRelaxation(model, collision=presets.guarded(dt, body_vertices=True),
                                          max_speed=self.max_speed, momentum=self.momentum, solver=SolverExplicit.name)
            relaxed = relaxation.relax(state, dt, max_iterations=self.iterations, min_iterations=self.min_iterations,
                                       on_log=on_log_and_save, resumed=RelaxResult(first_step, list(energy)),
                                       should_stop=stop)
        return Settled(state, relaxed.iterations, relaxed.iterations * dt, relaxed.converged), relaxed.energy


@dataclass(frozen=True)
class DampedDrape:
    """The implicit solver's drape: its steps (``sweeps`` a step), each followed by a drag of
    time constant ``memory`` [s] (near critical for a sleeve swinging down from the sewing
    pose) and a speed cap ``max_speed`` [m/s] (the terminal speed of a fall under that drag),
    until the shape is steady: over two checks ``check_every`` [s] apart, its nodes moved less
    than ``steady_mean`` [m] on average and 99 % of them less than ``steady_p99`` [m]; at most
    ``seconds`` [s] of simulated time. Not every node stops: truncated sweeps leave nodes
    jittering by tens of micrometres a step, and nodes at a coarse flared hem slip now and then,
    once the shape has stopped changing."""

    memory: float = 0.1
    max_speed: float = 0.5
    check_every: float = 0.5
    steady_mean: float = 1.0e-3
    steady_p99: float = 1.0e-2
    seconds: float = 10.0
    sweeps: int = DRAPE_SWEEPS

    def steps_planned(self) -> int:
        """The most checks it makes."""
        return int(self.seconds / self.check_every)

    def steady(self, before: np.ndarray, after: np.ndarray) -> bool:
        moved = np.linalg.norm(after - before, axis=1)
        return float(moved.mean()) < self.steady_mean and float(np.percentile(moved, 99)) < self.steady_p99

    def run(self, model: Model, state: State, first_step: int, energy: list[tuple[int, float]], on_save: Saver,
            progress: bool, stop: Stop | None = None) -> tuple[Settled, list[tuple[int, float]]]:
        """As :meth:`KineticDrape.run`, the energy logged at each check against the step."""
        energy = list(energy)
        with relax_progress("draping", self.steps_planned(), progress) as on_log:
            def on_check(step: int, state) -> None:
                energy.append((step, total_energy(model, state.positions())))
                on_log(len(energy), energy[-1][1], state)
                on_save(step, energy, state)

            settings = SettleSettings(memory=self.memory, check_every=self.check_every, max_seconds=self.seconds,
                                      rest_speed=0.0, steady=self.steady, max_speed=self.max_speed,
                                      iterations=self.sweeps)
            settled = settle(model, SolverImplicit.name, settings, state=state, on_check=on_check,
                             first_step=first_step, should_stop=stop)
        return settled, energy


DRAPING: dict[str, KineticDrape | DampedDrape] = {"explicit": KineticDrape(), "implicit": DampedDrape()}
"""How each solver drapes, by its name."""
