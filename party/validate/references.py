"""Reference solutions the cases compare with: the elastic catenary and the heavy elastica."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_bvp
from scipy.optimize import brentq


def elastic_catenary(length: float, span: float, weight: float, axial_stiffness: float,
                     samples: int = 401) -> np.ndarray:
    """Shape of a uniform elastic cable hung between two supports at equal height (Irvine,
    "Cable Structures", 1981): unstretched ``length`` [m], ``span`` [m], ``weight`` per unit
    unstretched length [N/m], ``axial_stiffness`` EA [N]. Returns (x, z) points [m], shape
    (samples, 2), from the left support at (0, 0), z up.

    With V = weight * length / 2 the vertical reaction, H the horizontal tension and s the
    unstretched arc length from the left support:

        x(s) = H s / EA + H / w [asinh(V / H) - asinh((V - w s) / H)]
        z(s) = (w s^2 / 2 - V s) / EA + (T(s) - T(0)) / w,  T(s) = sqrt(H^2 + (V - w s)^2)

    H is found from x(length) = span.
    """
    if not 0.0 < span:
        raise ValueError("span must be positive")
    w, ea, v = weight, axial_stiffness, 0.5 * weight * length

    def x_of(s, h):
        return h * s / ea + h / w * (np.arcsinh(v / h) - np.arcsinh((v - w * s) / h))

    def z_of(s, h):
        tension = np.sqrt(h * h + (v - w * s) ** 2)
        return (0.5 * w * s * s - v * s) / ea + (tension - math.hypot(h, v)) / w

    h = brentq(lambda h: x_of(length, h) - span, 1e-9 * w * length, 1e6 * w * length, xtol=1e-14, rtol=1e-13)
    s = np.linspace(0.0, length, samples)
    return np.stack([x_of(s, h), z_of(s, h)], axis=1)


def heavy_elastica(gamma: float, samples: int = 201) -> np.ndarray:
    """Shape of an inextensible cantilever bent by its own weight (the heavy elastica):

        theta'' = -gamma (1 - s) cos(theta),  theta(0) = 0,  theta'(1) = 0,

    with theta the slope below horizontal, s the arc length over the overhang and
    gamma = W L^3 / B (W weight per unit area [N/m^2], L overhang [m], B bending rigidity
    [N*m]). Returns (x, z) points per unit overhang, shape (samples, 2), from the clamp at
    (0, 0), z up (the tip below)."""
    s = np.linspace(0.0, 1.0, samples)

    def rhs(s, y):
        return np.vstack([y[1], -gamma * (1.0 - s) * np.cos(y[0])])

    def bc(ya, yb):
        return np.array([ya[0], yb[1]])

    guess = np.vstack([gamma / 6.0 * (3 * s - 3 * s**2 + s**3), gamma / 2.0 * (1 - s) ** 2])
    guess = np.clip(guess, -1.5, 1.5)
    solution = solve_bvp(rhs, bc, s, guess, tol=1e-8, max_nodes=100000)
    if not solution.success:
        raise RuntimeError(f"the elastica solve failed at gamma {gamma}: {solution.message}")
    theta = solution.sol(s)[0]
    ds = s[1] - s[0]
    x = np.concatenate([[0.0], np.cumsum(0.5 * (np.cos(theta[1:]) + np.cos(theta[:-1])) * ds)])
    z = -np.concatenate([[0.0], np.cumsum(0.5 * (np.sin(theta[1:]) + np.sin(theta[:-1])) * ds)])
    return np.stack([x, z], axis=1)


def chord_angle(shape: np.ndarray) -> float:
    """Angle [deg] below horizontal of the chord from the clamp to the tip of a shape."""
    tip = shape[-1] - shape[0]
    return math.degrees(math.atan2(-tip[1], tip[0]))


def distance_to_curve(points: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """Distance [m] from each 2-D point to the polyline ``curve``."""
    a, b = curve[:-1], curve[1:]
    ab = b - a
    t = np.clip(np.einsum("pk,sk->ps", points, ab) - np.einsum("sk,sk->s", a, ab), 0.0, None)
    t = np.clip(t / np.maximum(np.einsum("sk,sk->s", ab, ab), 1e-30), 0.0, 1.0)
    nearest = a[None] + t[..., None] * ab[None]
    return np.min(np.linalg.norm(points[:, None] - nearest, axis=2), axis=1)
