"""Case 3: the cantilever bending test (ASTM D1388, Peirce 1930).

A strip lies on a ledge and is pushed over its edge until the chord from the edge
to its tip falls 41.5 degrees below horizontal; half the overhang is the bending length c,
and the flexural rigidity is G = W c^3 (W the fabric's weight per unit area). For an ideal
heavy elastica the chord reaches 41.5 degrees at W L^3 / B = 8.00, so c = (B / W)^(1/3)
exactly, to about 0.1 %: the simulated c must lie within 3 % of that, and the strip's whole
deflected shape must follow the elastica (:func:`party.validate.references.heavy_elastica`)
within 3 % of the overhang.

The error is first order in the node spacing: the curvature jumps at the ledge's edge (flat on
the ledge, M / B just beyond), and the curvature stencil centred on the edge sees half of it
over its whole cell, so the root is too soft by about h / L. Case 8 measures the order.

Pushing is done as a search: the strip is settled at rest at a few overhangs (clamped on the
ledge, which the ruler of the standard's apparatus does), and the overhang that gives
41.5 degrees is interpolated from their chord angles. Bending hysteresis is left out here:
the test measures the rigidity B.
"""

from __future__ import annotations

import math

import numpy as np

from ..fabric import Fabric
from ..meshing import rectangular_net
from ..model import ModelBuilder
from ..units import GRAVITY
from .checks import CaseResult, Check
from .report import plot_rest_shape, save
from .references import chord_angle, distance_to_curve, heavy_elastica
from .simulate import settle_until_unchanged

NAME = "cantilever"
CHORD = 41.5  # degrees, ASTM D1388
GAMMA_AT_CHORD = 8.00  # W L^3 / B of the elastica whose chord is 41.5 degrees
LENGTH_TOLERANCE = 0.03  # relative, on the bending length
SHAPE_TOLERANCE = 0.03  # largest deviation over the overhang
WIDTH = 0.025  # m, the standard's strip
ROWS = 4  # spaces across the simulated strip (see overhang_shape)
SEGMENTS = {"quick": 40, "default": 60}  # spaces along the overhang
CLAMPED_COLUMNS = 2  # columns held on the ledge behind its edge
STEADY_CHORD = 2e-3
"""Change of the chord angle [degrees] over each of two windows below which the strip's shape
is read (:func:`~party.validate.simulate.settle_until_unchanged`, whose docstring says why a
speed alone will not do). A 1 % longer strip turns the chord by about 1 degree."""


def run_case(fabric: Fabric, solver: str, *, quick: bool = False, out=None) -> CaseResult:
    result = CaseResult(NAME)
    if fabric.bending_rigidity <= 0.0:
        result.details["skipped"] = f"fabric {fabric.name!r} has no bending rigidity"
        return result
    segments = SEGMENTS["quick" if quick else "default"]
    length, overhang, shape = bending_length_test(fabric, solver, segments)
    reference = reference_bending_length(fabric)
    result.checks.append(Check.relative(NAME, f"{fabric.name} bending length c [mm]", 500.0 * length, 1000.0 * reference,
                                        LENGTH_TOLERANCE))
    weight = fabric.areal_density * GRAVITY
    result.checks.append(Check.relative(NAME, f"{fabric.name} flexural rigidity G = W c^3 [uN*m]",
                                        1e6 * weight * (0.5 * length) ** 3, 1e6 * fabric.bending_rigidity,
                                        3.0 * LENGTH_TOLERANCE))
    gamma = weight * overhang**3 / fabric.bending_rigidity
    elastica = heavy_elastica(gamma) * overhang
    deviation = float(distance_to_curve(shape, elastica).max()) / overhang
    result.checks.append(Check.bound(NAME, f"deflected shape at W L^3 / B = {gamma:.2f}: largest deviation / overhang",
                                     deviation, SHAPE_TOLERANCE, "fraction of overhang"))
    result.details.update(bending_length_m=0.5 * length, overhang_m=overhang, gamma=gamma, shape=shape.tolist(),
                          elastica=elastica.tolist())
    if out is not None:
        result.plots.append(_plot(out, shape, elastica, fabric.name))
    return result


def reference_bending_length(fabric: Fabric) -> float:
    """c = (B / W)^(1/3) [m], the bending length the fabric's rigidity implies."""
    return (fabric.bending_rigidity / (fabric.areal_density * GRAVITY)) ** (1.0 / 3.0)


def bending_length_test(fabric: Fabric, solver: str, segments: int) -> tuple[float, float, np.ndarray]:
    """The overhang [m] at which the chord reaches 41.5 degrees (interpolated between the
    overhangs tried), and the tried overhang nearest it [m] with its strip's centre line as
    (x, z) from the ledge's edge [m]."""
    fabric = fabric.with_(bending_hysteresis=0.0)
    guess = 2.0 * reference_bending_length(fabric)
    tried = {o: overhang_shape(fabric, solver, o, segments) for o in (0.85 * guess, 1.15 * guess)}

    def estimate() -> float:
        ordered = sorted(tried)
        return _interpolate(np.log(ordered), np.array([chord_angle(tried[o]) for o in ordered]), CHORD)

    for _ in range(3):
        overhang = estimate()
        if not 0.5 * min(tried) < overhang < 2.0 * max(tried):
            break  # the chord is far from 41.5 degrees at every overhang tried: report what was found
        if min(abs(overhang - o) for o in tried) < 1e-4 * overhang:
            break
        tried[overhang] = overhang_shape(fabric, solver, overhang, segments)
        if abs(chord_angle(tried[overhang]) - CHORD) < 0.05:
            break
    best = min(tried, key=lambda o: abs(chord_angle(tried[o]) - CHORD))
    return estimate(), best, tried[best]


def overhang_shape(fabric: Fabric, solver: str, overhang: float, segments: int,
                   edge: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """The rest shape of a strip sticking ``overhang`` [m] out along x over the ledge, whose
    edge runs along y from ``edge`` [m]: its centre line as (x, z) [m] from the ledge's edge,
    the clamped part left out.

    The strip simulated is ROWS spaces wide rather than the standard's 25 mm: bending along
    the strip (Poisson's ratio 0) does not depend on the width, and the clamp's error is
    first order in the spacing along the strip (the curvature stencil at the ledge's edge
    straddles the clamp), which wants many nodes along it (case 8 measures the order)."""
    spacing = overhang / segments
    behind = CLAMPED_COLUMNS * spacing
    net = rectangular_net(overhang + behind, ROWS * spacing, spacing)
    u, v = net.uv[:, 0] - behind, net.uv[:, 1]
    builder = ModelBuilder()
    builder.add_cloth(net, fabric, np.c_[u, v, np.zeros(net.node_count)] + np.asarray(edge, float))
    builder.pin(np.flatnonzero(u < 1e-9 * overhang))
    model = builder.finalize()
    middle = np.abs(v - v[np.argmin(np.abs(v - 0.5 * v.max()))]) < 1e-9 * overhang
    ids = np.flatnonzero(middle & (u > -1e-9 * overhang))
    ids = ids[np.argsort(u[ids])]

    def centre_line(points: np.ndarray) -> np.ndarray:
        return points[ids][:, [0, 2]] - points[ids[0]][[0, 2]]

    state = settle_until_unchanged(model, solver, lambda p: chord_angle(centre_line(p)), STEADY_CHORD, collision=None)
    return centre_line(state.positions())


def _interpolate(x: np.ndarray, y: np.ndarray, target: float) -> float:
    """x where the piecewise-linear y(x) (sorted by x) meets ``target``, extrapolating from the
    end segments; returns exp(x) (x is a log)."""
    k = int(np.clip(np.searchsorted(y, target), 1, len(y) - 1))
    x0, x1, y0, y1 = x[k - 1], x[k], y[k - 1], y[k]
    return float(math.exp(x0 + (target - y0) * (x1 - x0) / (y1 - y0)))


def _plot(out, shape: np.ndarray, elastica: np.ndarray, fabric: str):
    fig, ax = plot_rest_shape(shape, elastica, simulated_label=f"{fabric}, simulated",
                              reference_label="heavy elastica", title="Cantilever bending test (ASTM D1388)",
                              unit="mm", scale=1000.0)
    tip = shape[-1] * 1000
    ax.plot([0, tip[0]], [0, tip[1]], "--", color="grey", lw=0.8, label=f"chord, {CHORD} deg")
    ax.axhline(0.0, color="grey", lw=0.5)
    ax.legend(fontsize=8)
    return save(fig, out / "cantilever.png")
