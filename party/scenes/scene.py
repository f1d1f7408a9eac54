"""What a scene hands to the runner."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..errors import InvalidInput
from ..model import Model


WHOLE_STEPS = 1.0e-6
"""Relative tolerance within which a duration counts as a whole number of steps."""


def check_timing(duration: float, dt: float) -> None:
    """Reject a scene's simulated time ``duration`` [s] or time step ``dt`` [s] that is not
    positive and finite, or a duration that is not a whole number of steps (a run would
    otherwise simulate another duration than the one asked for), before any set-up work."""
    if not 0 < duration < math.inf:
        raise InvalidInput(f"duration must be positive and finite, got {duration}")
    if not 0 < dt < math.inf:
        raise InvalidInput(f"time step must be positive and finite, got {dt}")
    steps = duration / dt
    if steps < 1.0 - WHOLE_STEPS:
        raise InvalidInput(f"the duration {duration:g} s is shorter than one step of {dt:g} s; give a longer "
                           "--duration or a smaller --dt")
    if abs(steps - round(steps)) > WHOLE_STEPS * steps:
        below, above = math.floor(steps) * dt, math.ceil(steps) * dt
        raise InvalidInput(f"the duration {duration:g} s is not a whole number of steps of {dt:g} s "
                           f"({steps:.4g} steps); give --duration {below:.6g} or {above:.6g}, or a --dt that divides it")


@dataclass
class Scene:
    """A ready-to-run simulation.

    Attributes:
        name: Scene name (as on the command line).
        model: The assembled model.
        solver: An object with ``step(state_in, state_out, control, dt)``.
        dt: Time step [s].
        duration: Simulated time [s].
        frame_interval: Simulated time between output frames [s].
        wind: Air velocity [m/s] as a function of time [s], or None for still air.
        view: Camera for pictures: matplotlib ``elev`` and ``azim`` [degrees].
        parameters: Scene settings echoed into ``summary.json``.
        summary: Further entries for ``summary.json`` known before the run (set-up results).
        pictures: ``pictures(out, frames)`` draws the run's pictures from the written frames
            (``frames``: list of (time [s], frame path)); None for the runner's default.
    """

    name: str
    model: Model
    solver: object
    dt: float
    duration: float
    frame_interval: float
    wind: Callable[[float], tuple[float, float, float]] | None = None
    view: dict = field(default_factory=lambda: {"elev": 15.0, "azim": -60.0})
    parameters: dict = field(default_factory=dict)
    summary: dict = field(default_factory=dict)
    pictures: Callable[[Path, list], None] | None = None
