"""What changes from step to step, and what a scene drives."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import warp as wp


@dataclass
class State:
    """The changing part of a simulation.

    Attributes:
        node_q: Node positions r [m], vec3, shape [node_count].
        node_qd: Node velocities dr/dt [m/s], vec3, shape [node_count].
        collider_q: Collider vertex positions [m], vec3.
        collider_qd: Collider vertex velocities [m/s], vec3 (enter eq. 12).
        hinge_slip: Where each bending stencil's hysteresis element has slipped to: its
            curvature vector at rest, in the stencil's own frame (along the thread, the
            normal, and across), vec3 [1/m] (see ``Model.hinge_friction``).
        time: Simulated time [s].
    """

    node_q: wp.array
    node_qd: wp.array
    collider_q: wp.array
    collider_qd: wp.array
    hinge_slip: wp.array
    time: float

    carried = ("node_q", "node_qd", "collider_q", "collider_qd", "hinge_slip", "time")
    """All of it (:mod:`party.solvers.memory`)."""

    def positions(self) -> np.ndarray:
        return self.node_q.numpy().astype(float)

    def velocities(self) -> np.ndarray:
        return self.node_qd.numpy().astype(float)

    def assign(self, other: "State") -> None:
        """Copy another state's values into this one (same model)."""
        wp.copy(self.node_q, other.node_q)
        wp.copy(self.node_qd, other.node_qd)
        wp.copy(self.collider_q, other.collider_q)
        wp.copy(self.collider_qd, other.collider_qd)
        wp.copy(self.hinge_slip, other.hinge_slip)
        self.time = other.time


@dataclass
class Control:
    """Inputs a scene drives.

    Attributes:
        wind: Air velocity [m/s], a 3-vector, uniform in space.
        kinematic_velocity: Velocity [m/s] imposed on kinematic nodes (pins: zero; handles: the
            handle's velocity), vec3 per node; ignored for free nodes.
    """

    wind: tuple[float, float, float]
    kinematic_velocity: wp.array
