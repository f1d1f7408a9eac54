"""Putting the flat panels around a body.

A panel with a placement goes where the placement says (GarmentCode's patterns carry one). A
panel without one is wrapped round the body part it belongs to:

- ``front``/``back``: its top at the body height named by its ``anchor``, each row of the panel
  bent round the torso's vertical axis on a half cylinder wide enough to clear the body at that
  height and to keep the row within a quarter turn either side of the centre front (or back);
- ``left_sleeve``/``right_sleeve``: rolled into a tube round a horizontal arm axis that leaves
  the shoulder sideways (the paper's initial shape: sleeves straight out), cap at the shoulder;
- ``left_leg``/``right_leg``: rolled into a tube round a vertical axis through the hip joint.

Panels are drawn upright as worn, seen from outside (x across, y up). Any node still inside the
body, or nearer to it than the clearance, is then moved out along the surface normal.
"""

from __future__ import annotations

import numpy as np

from ..body.body import Body
from ..body.probe import ColliderProbe
from ..errors import InvalidInput
from .assemble import Garment

CLEARANCE = 0.015
"""Initial distance kept between cloth and body [m]."""

COVERAGE = 0.47 * np.pi
"""Largest angle [rad] a wrapped torso panel row reaches either side of its centre line."""


def dress(garment: Garment, body: Body, *, device: str = "cpu") -> np.ndarray:
    """Initial 3-D node positions [m] of ``garment`` around ``body``, shape (n, 3)."""
    points = np.zeros((garment.node_count, 3))
    for k, mesh in enumerate(garment.panels):
        panel = mesh.panel
        sl = slice(garment.node_offsets[k], garment.node_offsets[k + 1])
        if panel.placement is not None:
            points[sl] = panel.placement.apply(mesh.xy)
        elif panel.part in ("front", "back"):
            points[sl] = _wrap_torso(mesh.xy, panel.outline(), body, panel.part, panel.anchor)
        elif panel.part in ("left_sleeve", "right_sleeve", "left_leg", "right_leg"):
            points[sl] = _roll_limb(mesh.xy, body, panel.part)
        else:
            raise InvalidInput(f"panel {panel.name!r} has neither a placement nor a body part to be placed on")
    return ColliderProbe(body.colliders, device).push_out(points, CLEARANCE)


def _half_width(y: np.ndarray, outline: np.ndarray, centre: float, band: float) -> np.ndarray:
    """Half width of the outline (from x = centre) near each height y."""
    near = np.abs(outline[None, :, 1] - y[:, None]) <= band
    span = np.where(near, np.abs(outline[None, :, 0] - centre), 0.0).max(axis=1)
    return np.maximum(span, 1e-3)


def _body_radius(body: Body, z: np.ndarray, band: float = 0.03) -> np.ndarray:
    """Torso radius [m] at each height (the nearest measured height outside the body's span)."""
    levels = np.linspace(z.min() - band, z.max() + band, 40)
    radii = np.array([body.torso_radius(h - band, h + band) for h in levels])
    return np.interp(z, levels, radii)


def _wrap_torso(xy: np.ndarray, outline: np.ndarray, body: Body, part: str, anchor: str) -> np.ndarray:
    centre = 0.5 * (outline[:, 0].min() + outline[:, 0].max())
    top = outline[:, 1].max()
    z = body.landmarks[anchor] - (top - xy[:, 1])
    spacing = max(np.ptp(outline[:, 1]) / 50.0, 0.01)
    width = _half_width(xy[:, 1], outline, centre, spacing)
    radius = np.maximum(_body_radius(body, z) + CLEARANCE, width / COVERAGE)
    angle = (xy[:, 0] - centre) / radius
    sign = 1.0 if part == "front" else -1.0
    ax, ay = body.axis
    return np.column_stack([ax + sign * radius * np.sin(angle), ay - sign * radius * np.cos(angle), z])


def _roll_limb(xy: np.ndarray, body: Body, part: str) -> np.ndarray:
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    centre = 0.5 * (lo[0] + hi[0])
    radius = (hi[0] - lo[0]) / (2 * np.pi * 0.9)
    angle = (xy[:, 0] - centre) / radius
    along = hi[1] - xy[:, 1]
    marks = body.landmarks
    if part.endswith("sleeve"):
        side = 1.0 if part == "left_sleeve" else -1.0  # facing -y, the left hand is at +x
        z = marks["shoulder"] - radius - CLEARANCE
        start = body.torso_radius(z - radius, z + radius) + CLEARANCE
        a = np.array([side, 0.0, 0.0])
        origin = np.array([body.axis[0] + side * start, body.axis[1], z])
        up = np.array([0.0, 0.0, 1.0])
    else:
        side = 1.0 if part == "left_leg" else -1.0
        origin = np.array([body.axis[0] + side * 0.09, body.axis[1], marks["hip"] - 0.05])
        a = np.array([0.0, 0.0, -1.0])
        up = np.array([0.0, -1.0, 0.0])
    b = np.cross(up, a)
    return (origin + along[:, None] * a + radius * (np.cos(angle)[:, None] * up + np.sin(angle)[:, None] * b))
