"""The benchmark scene: a square cloth dropped onto a sphere.

A 1 m square of N x N nodes lies flat 0.32 m above the top of a static sphere of radius 0.3 m
centred at the origin (Z up) and falls under gravity for 1 s, with cloth self-collision on or
off. Blender and Newton run the same scene in ``benchmarks/peers/``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..body import sphere
from ..collision import CollisionSettings
from ..errors import InvalidInput
from ..fabric import Fabric, fabric_by_name
from ..meshing import rectangular_net
from ..model import ModelBuilder
from ..solvers.registry import make_solver, solver_class
from .scene import Scene, check_timing

SPHERE_RADIUS = 0.3   # m
CLOTH_SIZE = 1.0      # m
DROP_HEIGHT = 0.62    # m, the cloth's plane above the sphere's centre
FABRIC = "cotton"     # the library fabric the scene drops (the peers are given it too)


@dataclass(frozen=True)
class Settings:
    """The sphere drop's options (``party run sphere-drop``): ``grid`` x ``grid`` nodes (default
    64, with ``quick`` 24), cloth-cloth collision on or off, the solver, the fabric (a library
    name or a Fabric), ``duration`` [s] (default 1, with ``quick`` 0.5) and the step ``dt`` [s]
    (default: the solver's)."""

    grid: int | None = None
    self_collision: bool = True
    solver: str = "implicit"
    fabric: Fabric | str = FABRIC
    duration: float | None = None
    dt: float | None = None
    quick: bool = False


def build(settings: Settings = Settings(), *, device: str | None = None, out: Path | None = None, resume: bool = False,
          progress: bool = False, on_save: Callable | None = None) -> Scene:
    """The sphere-drop scene as ``settings`` say, its kernels on ``device`` (``out``, ``resume``,
    ``progress`` and ``on_save``, which scenes that keep their set-up take, it has no use for)."""
    solver = settings.solver
    dt = solver_class(solver).default_dt if settings.dt is None else settings.dt
    grid = settings.grid if settings.grid is not None else 24 if settings.quick else 64
    duration = settings.duration if settings.duration is not None else 0.5 if settings.quick else 1.0
    check_timing(duration, dt)
    if not 2 <= grid <= 1000:
        raise InvalidInput(f"--grid must lie in 2-1000 nodes per side, got {grid}")
    fabric = fabric_by_name(settings.fabric) if isinstance(settings.fabric, str) else settings.fabric
    self_collision = settings.self_collision
    spacing = CLOTH_SIZE / (grid - 1)
    net = rectangular_net(CLOTH_SIZE, CLOTH_SIZE, spacing)
    builder = ModelBuilder()
    builder.add_cloth(net, fabric, np.c_[net.uv - CLOTH_SIZE / 2, np.full(net.node_count, DROP_HEIGHT)], name="cloth")
    builder.add_collider(sphere(SPHERE_RADIUS, subdivisions=4))
    model = builder.finalize(device)
    collision = CollisionSettings(cloth=self_collision)
    return Scene(
        name="sphere-drop", model=model, solver=make_solver(solver, model, collision=collision), dt=dt,
        duration=duration, frame_interval=1.0 / 30.0, view={"elev": 25.0, "azim": -60.0},
        parameters={"grid": grid, "self_collision": self_collision, "solver": solver, "spacing_m": spacing,
                    "sphere_radius_m": SPHERE_RADIUS, "fabric": fabric.to_dict()},
    )
