"""A body to dress: its collider meshes, landmark heights, and the frame it came in.

Inside party a body is Z up, facing -y, in metres. :class:`Body` remembers the
rotation and scale from the file's frame so that results can be written back in it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .collider import ColliderMesh

LANDMARK_FRACTIONS = {"hip": 0.50, "waist": 0.62, "bust": 0.72, "shoulder": 0.81, "neck": 0.83}
"""Landmark heights as fractions of stature, for bodies that do not give their own (adult
proportions, after the standard anthropometric tables)."""


@dataclass(frozen=True)
class Body:
    """A body and what dressing needs to know about it.

    Attributes:
        name: Label for messages and files.
        colliders: Closed meshes [m], in our frame (Z up, front towards -y).
        landmarks: Heights [m] of ``neck``, ``shoulder``, ``bust``, ``waist``, ``hip`` and the
            ``top``; ``shoulder_half_width`` [m] (centre to shoulder point).
        axis: (x, y) of the torso's vertical axis [m].
        to_source: Rotation (3, 3) taking our frame to the file's frame.
        measurements: GarmentCode's measurements of the body where its file has them
            (:mod:`party.body.measurements`: lengths [m], angles [deg]); empty otherwise.
    """

    name: str
    colliders: tuple[ColliderMesh, ...]
    landmarks: dict
    axis: tuple[float, float] = (0.0, 0.0)
    to_source: np.ndarray = field(default_factory=lambda: np.eye(3))
    measurements: dict = field(default_factory=dict)

    def vertices(self) -> np.ndarray:
        return np.concatenate([c.vertices for c in self.colliders])

    def to_file_frame(self, points: np.ndarray) -> np.ndarray:
        """Points [m, our frame] turned into the body file's axes (still metres)."""
        return np.asarray(points, float) @ self.to_source.T

    def torso_radius(self, z_lo: float, z_hi: float) -> float:
        """Largest horizontal distance [m] from the torso axis of body points between two
        heights, counting only points within 0.35 m of the axis (arms left out)."""
        v = self.vertices()
        d = np.hypot(v[:, 0] - self.axis[0], v[:, 1] - self.axis[1])
        sel = (v[:, 2] >= z_lo) & (v[:, 2] <= z_hi) & (d < 0.35)
        return float(d[sel].max()) if sel.any() else 0.15


def landmarks_from_stature(vertices: np.ndarray) -> dict:
    """Landmark heights [m] of a standing body from its stature (see :data:`LANDMARK_FRACTIONS`)."""
    z0, z1 = float(vertices[:, 2].min()), float(vertices[:, 2].max())
    height = z1 - z0
    marks = {k: z0 + f * height for k, f in LANDMARK_FRACTIONS.items()}
    near = vertices[np.abs(vertices[:, 2] - marks["shoulder"]) < 0.02]
    marks["shoulder_half_width"] = float(np.abs(near[:, 0]).max()) * 0.85 if len(near) else 0.19
    marks["top"] = z1
    return marks
