"""The paper's dress form (section 7): a body made of stacked elliptical cross-sections fitted
to a few standard measurements, meshed as a closed triangle surface with outward normals.

Cross-sections sit at fixed fractions of stature (adult proportions); each is an ellipse whose
perimeter equals the measured girth at that level, with a depth-to-width ratio typical of the
level. A smooth curve through the levels gives the rings in between. Arms, when asked for, are
elliptical tubes hanging from the shoulder points in an A-pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator

from ..errors import InvalidInput
from .body import Body
from .collider import ColliderMesh


@dataclass(frozen=True)
class Measurements:
    """Standard body measurements [m] (girths are circumferences)."""

    height: float = 1.68
    bust: float = 0.90
    waist: float = 0.72
    hip: float = 0.96
    shoulder_width: float = 0.39
    neck: float = 0.35
    arm_length: float = 0.58
    upper_arm: float = 0.28

    def check(self) -> None:
        for name, value in self.__dict__.items():
            if not (np.isfinite(value) and value > 0):
                raise InvalidInput(f"body measurement {name} must be positive, got {value}")
        if not 1.0 <= self.height <= 2.5:
            raise InvalidInput(f"body height {self.height} m is implausible (expected 1.0-2.5 m)")
        if not self.waist < max(self.bust, self.hip) * 1.3:
            raise InvalidInput("waist girth is implausibly large for the bust and hip girths")


SIZES = {
    "S": Measurements(1.64, 0.84, 0.66, 0.90, 0.37, 0.33, 0.57, 0.26),
    "M": Measurements(1.68, 0.90, 0.72, 0.96, 0.39, 0.35, 0.58, 0.28),
    "L": Measurements(1.70, 0.98, 0.82, 1.04, 0.41, 0.37, 0.59, 0.30),
}
"""Standard women's sizes (after EN 13402-3 size tables)."""


def ellipse_semi_axes(girth: float, ratio: float) -> tuple[float, float]:
    """Semi-axes (a, b = ratio a) [m] of the ellipse of perimeter ``girth`` (Ramanujan)."""
    h = ((1 - ratio) / (1 + ratio)) ** 2
    per_a = np.pi * (1 + ratio) * (1 + 3 * h / (10 + np.sqrt(4 - 3 * h)))
    a = girth / per_a
    return float(a), float(ratio * a)


def _levels(m: Measurements) -> np.ndarray:
    """(height fraction, half width, half depth, forward shift) of the key cross-sections."""
    hip = ellipse_semi_axes(m.hip, 0.72)
    waist = ellipse_semi_axes(m.waist, 0.72)
    bust = ellipse_semi_axes(m.bust, 0.72)
    under = ellipse_semi_axes(0.5 * (m.bust + m.waist) + 0.02, 0.72)
    neck = ellipse_semi_axes(m.neck, 0.9)
    s = 0.5 * m.shoulder_width
    rows = [
        (0.440, 0.93 * hip[0], 0.93 * hip[1], 0.0),
        (0.500, *hip, 0.0),
        (0.560, 0.5 * (hip[0] + waist[0]), 0.5 * (hip[1] + waist[1]), 0.0),
        (0.620, *waist, 0.0),
        (0.690, *under, 0.005),
        (0.720, *bust, 0.015),
        (0.760, 0.5 * (bust[0] + s), 0.9 * bust[1], 0.008),
        (0.795, 0.98 * s, 0.75 * bust[1], 0.0),
        (0.812, 0.90 * s, 0.58 * bust[1], 0.0),
        (0.824, 0.55 * s, 0.45 * bust[1], 0.0),
        (0.834, 1.05 * neck[0], 1.05 * neck[1], 0.0),
        (0.870, *neck, 0.0),
    ]
    return np.array(rows)


def _tube(centres: np.ndarray, axes_u: np.ndarray, axes_v: np.ndarray, a: np.ndarray, b: np.ndarray,
          around: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed tube of elliptical rings (ring k: centre, in-plane unit axes u, v, semi-axes a,
    b) with flat caps; faces counter-clockwise seen from outside when u x v runs along the tube."""
    theta = np.linspace(0.0, 2 * np.pi, around, endpoint=False)
    rings = (centres[:, None, :] + a[:, None, None] * np.cos(theta)[None, :, None] * axes_u[:, None, :]
             + b[:, None, None] * np.sin(theta)[None, :, None] * axes_v[:, None, :])
    n = len(centres)
    verts = np.vstack([rings.reshape(-1, 3), centres[0], centres[-1]])
    idx = np.arange(n * around).reshape(n, around)
    nxt = np.roll(idx, -1, axis=1)
    quads_a = np.stack([idx[:-1], nxt[:-1], nxt[1:]], axis=-1).reshape(-1, 3)
    quads_b = np.stack([idx[:-1], nxt[1:], idx[1:]], axis=-1).reshape(-1, 3)
    bottom, top = n * around, n * around + 1
    cap_lo = np.stack([np.full(around, bottom), nxt[0], idx[0]], axis=1)
    cap_hi = np.stack([np.full(around, top), idx[-1], nxt[-1]], axis=1)
    return verts, np.vstack([quads_a, quads_b, cap_lo, cap_hi]).astype(np.int32)


def dress_form(size: str | Measurements = "M", *, arms: bool = False, rings: int = 72, around: int = 64) -> Body:
    """The dress form of a standard ``size`` (see :data:`SIZES`) or of given measurements."""
    if isinstance(size, str):
        if size not in SIZES:
            raise InvalidInput(f"unknown body size {size!r} (presets: {', '.join(SIZES)})")
        m = SIZES[size]
    else:
        m = size
    m.check()
    lv = _levels(m)
    z = np.linspace(lv[0, 0], lv[-1, 0], rings) * m.height
    a = PchipInterpolator(lv[:, 0] * m.height, lv[:, 1])(z)
    b = PchipInterpolator(lv[:, 0] * m.height, lv[:, 2])(z)
    fwd = PchipInterpolator(lv[:, 0] * m.height, lv[:, 3])(z)
    centres = np.column_stack([np.zeros(rings), -fwd, z])
    ex, ey = np.tile([1.0, 0.0, 0.0], (rings, 1)), np.tile([0.0, 1.0, 0.0], (rings, 1))
    verts, faces = _tube(centres, ex, ey, a, b, around)
    colliders = [ColliderMesh("dress_form", verts, faces)]
    landmarks = {k: float(f * m.height) for k, f in
                 (("hip", 0.50), ("waist", 0.62), ("bust", 0.72), ("shoulder", 0.812), ("neck", 0.834))}
    landmarks["top"] = float(z[-1])
    landmarks["shoulder_half_width"] = float(0.5 * m.shoulder_width)
    if arms:
        colliders += [_arm(m, side) for side in (-1.0, 1.0)]
    name = size if isinstance(size, str) else "custom"
    return Body(f"dress_form_{name}", tuple(colliders), landmarks)


def _arm(m: Measurements, side: float) -> ColliderMesh:
    """An arm hanging 20 degrees out from the body, starting inside the shoulder."""
    top = np.array([side * 0.5 * m.shoulder_width * 0.88, 0.0, 0.80 * m.height])
    angle = np.radians(20.0)
    direction = np.array([side * np.sin(angle), 0.0, -np.cos(angle)])
    k = 24
    s = np.linspace(0.0, m.arm_length, k)
    centres = top + s[:, None] * direction
    radius = np.interp(s, [0, 0.3 * m.arm_length, m.arm_length],
                       [m.upper_arm / (2 * np.pi), m.upper_arm / (2 * np.pi) * 0.95, 0.025])
    u = np.tile([0.0, 1.0, 0.0], (k, 1))
    v = np.tile(np.cross(direction, [0.0, 1.0, 0.0]), (k, 1))
    verts, faces = _tube(centres, u, v, radius, radius * 0.9, 32)
    return ColliderMesh("left_arm" if side > 0 else "right_arm", verts, faces)
