"""Case 5: restitution. A node dropped on a floor leaves it with sigma times the normal speed
it arrived with (eq. 11), whatever the solver."""

from __future__ import annotations

import numpy as np

from ..body import floor
from ..fabric import Fabric
from ..model import ModelBuilder
from .checks import CaseResult, Check
from ..solvers.registry import solver_class
from .simulate import run

NAME = "restitution"
TOLERANCE = 0.01  # relative
DROP_HEIGHTS = (0.05, 0.2)  # m above the contact layer
SIDE_SPEED = 0.3  # m/s along the floor: only the normal speed is restituted


def run_case(fabric: Fabric, solver: str, *, quick: bool = False, out=None) -> CaseResult:
    result = CaseResult(NAME)
    for height in DROP_HEIGHTS:
        ratio = bounce_ratio(fabric, solver, height)
        result.checks.append(Check.relative(NAME, f"rebound / arrival normal speed, dropped {height * 100:.0f} cm [-]",
                                            ratio, fabric.restitution, TOLERANCE))
    return result


def bounce_ratio(fabric: Fabric, solver: str, height: float) -> float:
    """Normal speed just after the first bounce over the speed the node arrives with (its
    velocity one step of gravity after the last free step)."""
    builder = ModelBuilder()
    node = builder.add_node((0.0, 0.0, fabric.thickness + height), 1e-4, fabric=fabric)
    builder.add_collider(floor(0.0, size=4.0))
    model = builder.finalize()
    dt = solver_class(solver).dynamics_step(model)
    g = -model.gravity[2]
    state = model.state(velocity=(SIDE_SPEED, 0.0, 0.0))
    previous = state.velocities()[node, 2]
    speeds = []
    fall = np.sqrt(2.0 * g * height) / g

    def observe(s):
        speeds.append(float(s.node_qd.numpy()[node, 2]))

    run(model, solver, fall + 0.01, dt=dt, observe=observe)
    vz = np.asarray([previous, *speeds])
    up = np.flatnonzero(vz > 0.0)
    if len(up) == 0:
        return 0.0
    k = up[0]
    arrival = vz[k - 1] - g * dt
    return float(vz[k] / -arrival)
