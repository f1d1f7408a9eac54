"""Case 2: the catenary. A chain of nodes and a cloth strip, each hung from two pins at equal
height, come to rest on the elastic catenary of their length, span, weight and stretch
stiffness (:func:`party.validate.references.elastic_catenary`); the largest distance of a
node from that curve must stay within 1 % of the span."""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from ..fabric import Fabric
from ..meshing import rectangular_net
from ..model import ModelBuilder
from ..units import GRAVITY
from .checks import CaseResult, Check
from .report import plot_rest_shape, save
from .references import distance_to_curve, elastic_catenary
from .simulate import settle_until_unchanged

NAME = "catenary"
TOLERANCE = 0.01  # largest deviation over span
LENGTH, SPAN, WIDTH = 0.5, 0.4, 0.04  # m
SPACINGS = {"quick": 0.02, "default": 0.01}
STEADY_DEVIATION = 1e-5
"""Change of the largest deviation over the span below which the hanging shape is read
(:func:`~party.validate.simulate.settle_until_unchanged`): a thousandth of the case's
tolerance."""


def run_case(fabric: Fabric, solver: str, *, quick: bool = False, out=None) -> CaseResult:
    result = CaseResult(NAME)
    spacing = SPACINGS["quick" if quick else "default"]
    chain, reference = hang_chain(fabric, solver, spacing)
    result.checks.append(Check.bound(NAME, "chain: largest deviation / span", _deviation(chain, reference) / SPAN,
                                     TOLERANCE, "fraction of span"))
    strip, reference = hang_strip(fabric, solver, spacing)
    result.checks.append(Check.bound(NAME, f"{fabric.name} strip: largest deviation / span",
                                     _deviation(strip, reference) / SPAN, TOLERANCE, "fraction of span"))
    result.details["strip"] = {"simulated": strip.tolist(), "reference": reference.tolist()}
    if out is not None:
        result.plots.append(_plot(out, strip, reference, fabric.name))
    return result


def strip_deviation(fabric: Fabric, solver: str, spacing: float) -> float:
    """The strip's largest deviation over the span at one spacing [m] (for convergence)."""
    strip, reference = hang_strip(fabric, solver, spacing)
    return _deviation(strip, reference) / SPAN


def hang_chain(fabric: Fabric, solver: str, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """A chain standing for a strip WIDTH wide: nodes every ``spacing`` [m] of its LENGTH,
    their masses and springs from the fabric. Returns the rest (x, z) of its nodes and the
    reference curve."""
    count = int(round(LENGTH / spacing)) + 1
    segment = LENGTH / (count - 1)
    mass = fabric.areal_density * WIDTH * segment
    builder = ModelBuilder()
    points = _v_shape(np.linspace(0.0, LENGTH, count))
    ids = [builder.add_node(p, mass if 0 < k < count - 1 else 0.5 * mass, fabric=fabric) for k, p in enumerate(points)]
    builder.pin([ids[0], ids[-1]])
    axial = fabric.tensile_warp * WIDTH
    builder.add_springs(np.c_[ids[:-1], ids[1:]], stiffness=axial / segment,
                        damping=fabric.damping * WIDTH * segment, rest_length=segment)
    model = builder.finalize()
    reference = elastic_catenary(LENGTH, SPAN, fabric.areal_density * WIDTH * GRAVITY, axial)
    rest = _settle_shape(model, solver, lambda p: p[:, [0, 2]], reference)
    return rest, reference


def hang_strip(fabric: Fabric, solver: str, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """A cloth strip LENGTH by WIDTH (warp along its length) pinned along both ends. Returns the
    rest (x, z) of its centre line's nodes and the reference curve."""
    net = rectangular_net(LENGTH, WIDTH, spacing)
    u, v = net.uv[:, 0], net.uv[:, 1]
    builder = ModelBuilder()
    builder.add_cloth(net, fabric, np.insert(_v_shape(u)[:, [0, 2]], 1, v, axis=1))
    builder.pin(np.flatnonzero((u < 1e-9) | (u > LENGTH - 1e-9)))
    model = builder.finalize()
    middle = np.abs(v - 0.5 * WIDTH) < 0.25 * spacing
    if not middle.any():  # an odd number of rows has its centre between two of them
        middle = np.abs(v - v[np.argmin(np.abs(v - 0.5 * WIDTH))]) < 1e-9
    reference = elastic_catenary(LENGTH, SPAN, fabric.areal_density * WIDTH * GRAVITY, fabric.tensile_warp * WIDTH)
    return _settle_shape(model, solver, lambda p: p[middle][:, [0, 2]], reference), reference


def _settle_shape(model, solver: str, line: Callable[[np.ndarray], np.ndarray], reference: np.ndarray) -> np.ndarray:
    """Settle ``model`` and return ``line(positions)`` at rest, (x, z) [m]: at rest by the
    solver's speed, or once the line's largest deviation from ``reference`` has stopped
    changing (:data:`STEADY_DEVIATION`)."""
    state = settle_until_unchanged(model, solver, lambda p: _deviation(line(p), reference), STEADY_DEVIATION * SPAN,
                                   collision=None)
    return line(state.positions())


def _v_shape(s: np.ndarray) -> np.ndarray:
    """Start shape: two straight legs of LENGTH / 2 from pins SPAN apart (x, y = 0, z)."""
    drop = math.sqrt((0.5 * LENGTH) ** 2 - (0.5 * SPAN) ** 2)
    half = 0.5 * LENGTH
    t = np.where(s <= half, s / half, (LENGTH - s) / half)
    x = np.where(s <= half, 0.5 * SPAN * t, SPAN - 0.5 * SPAN * t)
    return np.stack([x, np.zeros_like(s), -drop * t], axis=1)


def _deviation(points: np.ndarray, reference: np.ndarray) -> float:
    return float(distance_to_curve(points, reference).max())


def _plot(out, strip: np.ndarray, reference: np.ndarray, fabric: str):
    fig, ax = plot_rest_shape(strip, reference, simulated_label=f"{fabric} strip, simulated",
                              reference_label="elastic catenary", title="Catenary: rest shape", unit="cm",
                              scale=100.0, size=(6.0, 3.5))
    ax.legend(loc="lower right", fontsize=8)
    return save(fig, out / "catenary.png")
