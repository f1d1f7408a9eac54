"""Bending hinges: the interior edges of a cloth's triangles, for dihedral bending.

Bending follows the quadratic model of Bergou, Wardetzky, Harmon, Zorin and Grinspun, "A
Quadratic Bending Model for Inextensible Surfaces" (SGP 2006): for an interior edge (a, b)
with opposite corners c and d in its two triangles, the discrete mean-curvature vector
k = sum_i K_i x_i uses cotangent weights of the flat rest triangles, and the hinge's energy is

    E = B / (A_0 + A_1) |k|^2 / 2            [J]

with B the bending rigidity [N*m] and A_0, A_1 the rest areas [m^2]. Bergou et al. scale by
3 / (A_0 + A_1); on our grain-aligned grids that stores three times the plate's energy, so the
factor here makes a cloth bent along its warp or weft onto a cylinder of radius R store
B / (2 R^2) per unit area, the energy density of a plate of rigidity B (tested, within 1.5 %
at 5 mm spacing). Bent along the bias (45 degrees) the same grid stores 1.5 times as much: the
grid's bending is anisotropic, as woven cloth's is, but by the mesh rather than the weave.
The energy is quadratic in the positions, so its forces are linear and its Hessian is
constant: cheap for the explicit solver, exact for the implicit one. The rest shape is flat,
as a pattern is.
"""

from __future__ import annotations

import numpy as np

from .net import ClothNet


def hinges(net: ClothNet) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The hinges of ``net``: nodes (a, b, c, d) per hinge, shape (h, 4) int; cotangent weights
    K, shape (h, 4); and 1 / (A_0 + A_1) [1/m^2], shape (h,). Edges of one triangle only
    (boundaries) and edges of more than two (non-manifold seams) carry no hinge."""
    tri = np.asarray(net.triangles, np.int64)
    if len(tri) == 0:
        return np.zeros((0, 4), np.int32), np.zeros((0, 4)), np.zeros(0)
    corner_uv = net.rest_triangle_uv()
    cot = _corner_cotangents(corner_uv)
    area = net.rest_triangle_areas()
    sides = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    owner = np.tile(np.arange(len(tri)), 3)
    slot = np.repeat(np.arange(3), len(tri))
    key = np.sort(sides, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    key, sides, owner, slot = key[order], sides[order], owner[order], slot[order]
    _, starts, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    first = starts[counts == 2]  # edges of exactly two triangles, listed at first and first + 1
    second = first + 1
    t0, t1 = owner[first], owner[second]
    s0, s1 = slot[first], slot[second]
    a, b = sides[first, 0], sides[first, 1]
    c = tri[t0, (s0 + 2) % 3]
    d = tri[t1, (s1 + 2) % 3]
    # cotangent of the interior angle at a and at b in each triangle
    cot_a0, cot_b0 = cot[t0, s0], cot[t0, (s0 + 1) % 3]
    local_a1 = np.where(tri[t1, s1] == a, s1, (s1 + 1) % 3)
    local_b1 = np.where(tri[t1, s1] == a, (s1 + 1) % 3, s1)
    cot_a1, cot_b1 = cot[t1, local_a1], cot[t1, local_b1]
    weights = np.stack([cot_b0 + cot_b1, cot_a0 + cot_a1, -(cot_a0 + cot_b0), -(cot_a1 + cot_b1)], axis=1)
    nodes = np.stack([a, b, c, d], axis=1).astype(np.int32)
    return nodes, weights, 1.0 / (area[t0] + area[t1])


def bending_energy(points: np.ndarray, nodes: np.ndarray, weights: np.ndarray, scale: np.ndarray,
                   rigidity: float) -> float:
    """Total hinge energy [J] of ``points`` [m] for bending rigidity ``rigidity`` [N*m]."""
    k = np.einsum("hk,hkc->hc", weights, points[nodes])
    return float(0.5 * rigidity * np.sum(scale * np.sum(k * k, axis=1)))


def _corner_cotangents(corner_uv: np.ndarray) -> np.ndarray:
    """cot of the interior angle at each corner of each triangle, shape (t, 3)."""
    out = np.empty(corner_uv.shape[:2])
    for k in range(3):
        u = corner_uv[:, (k + 1) % 3] - corner_uv[:, k]
        w = corner_uv[:, (k + 2) % 3] - corner_uv[:, k]
        cross = np.abs(u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0])
        out[:, k] = (u * w).sum(axis=1) / np.maximum(cross, 1e-30)
    return out
