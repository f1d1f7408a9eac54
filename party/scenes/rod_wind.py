"""Experiment 1 of the paper (section 7, figure 11): cloth over a rod in a cross wind.

A rectangle of wool flannel (Table 1) hangs over a horizontal rod, half on each side. Wind
blows across the rod (along +x), rising over the first 0.2 s. The windward half is pushed into
the leeward half, which it shields from the wind: the scene exercises cloth-rod contact with
friction (eqs. 8-12) and cloth-cloth contact (eqs. 13-14) together.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..body import rod
from ..collision import CollisionSettings
from ..errors import InvalidInput
from ..fabric import Fabric, wool_flannel
from ..meshing import rectangular_net
from ..model import ModelBuilder
from ..solvers import Air
from ..solvers.registry import make_solver, solver_class
from .scene import Scene, check_timing

ROD_HEIGHT = 1.0      # m, rod axis above the floor
ROD_RADIUS = 0.015    # m
ROD_LENGTH = 0.8      # m, along y


def draped_over_rod(uv: np.ndarray, length: float, radius: float, height: float) -> np.ndarray:
    """Place a flat cloth (u across the rod's axis y, v along its length) over a rod at
    ``height`` so that it hangs straight down on both sides of a half-circle of ``radius``;
    arc length is preserved, so the cloth starts unstretched."""
    side = (length - np.pi * radius) / 2.0
    s = uv[:, 1]
    x = np.empty_like(s)
    z = np.empty_like(s)
    down = s < side
    x[down], z[down] = -radius, height - (side - s[down])
    over = (s >= side) & (s <= side + np.pi * radius)
    angle = (s[over] - side) / radius
    x[over], z[over] = -radius * np.cos(angle), height + radius * np.sin(angle)
    up = s > side + np.pi * radius
    x[up], z[up] = radius, height - (s[up] - side - np.pi * radius)
    y = uv[:, 0] - uv[:, 0].max() / 2.0
    return np.stack([x, y, z], axis=1)


@dataclass(frozen=True)
class Settings:
    """The rod-in-the-wind options (``party run rod-wind``): the net's node ``spacing`` [m]
    (default 12.5 mm, with ``quick`` 25 mm), ``duration`` [s] (default 1, with ``quick`` 0.2),
    ``wind_speed`` [m/s], the step ``dt`` [s] (default: the solver's, the paper's 1e-4 s for the
    explicit one), the cloth's ``width`` and ``length`` [m], the fabric (default: the paper's
    wool flannel), the time between frames [s] and the solver."""

    spacing: float | None = None
    duration: float | None = None
    wind_speed: float = 4.0
    dt: float | None = None
    width: float = 0.5
    length: float = 0.9
    fabric: Fabric | None = None
    frame_interval: float = 0.02
    solver: str = "explicit"
    quick: bool = False


def build(settings: Settings = Settings(), *, device: str | None = None, out: Path | None = None, resume: bool = False,
          progress: bool = False, on_save: Callable | None = None) -> Scene:
    """The rod-in-the-wind scene as ``settings`` say, its kernels on ``device`` (``out``,
    ``resume``, ``progress`` and ``on_save``, which scenes that keep their set-up take, it has no
    use for)."""
    solver, quick = settings.solver, settings.quick
    dt = solver_class(solver).default_dt if settings.dt is None else settings.dt
    spacing = settings.spacing if settings.spacing is not None else 0.025 if quick else 0.0125
    duration = settings.duration if settings.duration is not None else 0.2 if quick else 1.0
    width, length, wind_speed, frame_interval = settings.width, settings.length, settings.wind_speed, \
        settings.frame_interval
    check_timing(duration, dt)
    if not spacing > 0 or spacing > length / 4:
        raise InvalidInput(f"spacing must be positive and below {length / 4} m, got {spacing}")
    if not math.isfinite(wind_speed):
        raise InvalidInput(f"--wind must be a finite speed in m/s, got {wind_speed}")
    fabric = settings.fabric or wool_flannel()
    net = rectangular_net(width, length, spacing)
    clearance = ROD_RADIUS + 1.5 * fabric.thickness
    builder = ModelBuilder()
    builder.add_cloth(net, fabric, draped_over_rod(net.uv, length, clearance, ROD_HEIGHT), name="flannel")
    builder.add_collider(rod(ROD_LENGTH, ROD_RADIUS, center=(0.0, 0.0, ROD_HEIGHT), axis=(0.0, 1.0, 0.0)))
    model = builder.finalize(device)
    integrator = make_solver(solver, model, collision=CollisionSettings(), air=Air())

    def wind(t: float) -> tuple[float, float, float]:
        return (wind_speed * min(t / 0.2, 1.0), 0.0, 0.0)

    return Scene(
        name="rod-wind", model=model, solver=integrator, dt=dt, duration=duration, frame_interval=frame_interval,
        wind=wind, view={"elev": 10.0, "azim": -70.0},
        parameters={"spacing_m": spacing, "wind_speed_m_per_s": wind_speed, "cloth_m": [width, length],
                    "rod_radius_m": ROD_RADIUS, "fabric": fabric.to_dict(), "solver": solver},
    )
