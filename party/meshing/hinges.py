"""Bending stencils of a grain-aligned net: curvature along the threads and twist of the quads.

Each stencil takes a few nodes i with fixed weights K_i and measures k = sum_i K_i x_i, a
curvature vector that vanishes for the flat rest pattern in any rigid pose; its energy is

    E = B * scale / 2 * |k|^2                [J]

with B the bending rigidity [N*m]. Two kinds, which together store the energy of a plate of
rigidity B and Poisson's ratio 0, B / 2 (k_uu^2 + k_vv^2 + 2 k_uv^2) per unit area:

- **Thread stencils**: three consecutive nodes j, i, k on one straight line of the net (a warp
  or weft thread), at distances l1 and l2 from i: the second difference
  K = (2 / (l1 (l1 + l2)), -2 / (l1 l2), 2 / (l2 (l1 + l2))) gives the curvature along the
  thread; scale = width * (l1 + l2) / 2, the area of fabric the stencil stands for (width
  from the net's elements).
- **Twist stencils**: the four corners of a quad of the grid (two triangles forming a
  parallelogram), diagonal corners a, b and the other two c, d: K = (1, 1, -1, -1) / A gives
  k_uv; scale = 2 A, with A the quad's area.

A cloth bent onto a cylinder of radius R along any direction stores B / (2 R^2) per unit area
(tested along the grain and the bias). The energy is quadratic in the positions, so its forces
are linear and its Hessian is constant: cheap for the explicit solver, exact for the implicit
one.

Why not dihedral hinges on the triangles' edges (Bergou et al. 2006, or discrete shells):
on a grid cut into right triangles, the hinge across a weft edge sees the curvature of only
the row where its triangles' right angles sit, so every row carries curvature at every other
node and can fold freely at the rest. A 25 mm cantilever strip of such hinges bent 27 % too
far at 40 nodes along it, and 57 % at 5 (``party validate --case cantilever``).

Nodes without both neighbours on a straight thread (along the outline of a cut panel, and
across seams whose threads do not line up) carry no thread stencil through them.
"""

from __future__ import annotations

import numpy as np

from .net import ClothNet, ElementKind

COLLINEAR = 1e-6
"""Largest sine of the angle between two threads through a node that still counts as one
straight thread, and the largest relative misfit of a parallelogram."""

THREADS = (ElementKind.WARP, ElementKind.WEFT)


def hinges(net: ClothNet) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The bending stencils of ``net``: nodes per stencil, shape (h, 4) int (the fourth node of
    a thread stencil is a neighbour across the thread, with weight 0: it gives the stencil's
    frame); weights K, shape (h, 4) [1/m^2]; and the scale [m^2], shape (h,), with stiffness
    B * scale."""
    threads = _thread_stencils(net)
    twists = _twist_stencils(net)
    nodes = np.concatenate([threads[0], twists[0]]).astype(np.int32)
    weights = np.concatenate([threads[1], twists[1]])
    scale = np.concatenate([threads[2], twists[2]])
    return nodes, weights, scale


def bending_energy(points: np.ndarray, nodes: np.ndarray, weights: np.ndarray, scale: np.ndarray,
                   rigidity: float) -> float:
    """Total bending energy [J] of ``points`` [m] for bending rigidity ``rigidity`` [N*m]."""
    k = np.einsum("hk,hkc->hc", weights, points[nodes])
    return float(0.5 * rigidity * np.sum(scale * np.sum(k * k, axis=1)))


def _thread_stencils(net: ClothNet):
    """Three nodes in a row on a warp or weft thread, found from the net's elements."""
    empty = (np.zeros((0, 4), np.int64), np.zeros((0, 4)), np.zeros(0))
    thread = np.isin(net.kinds, THREADS)
    e = np.asarray(net.elements, np.int64)[thread]
    if len(e) == 0:
        return empty
    widths = np.asarray(net.widths, float)[thread]
    rest = net.element_rest_lengths()[thread]
    span = net.uv[e[:, 1]] - net.uv[e[:, 0]]
    length = np.linalg.norm(span, axis=1)
    # Only elements whose flat-pattern span is their rest length: a seam node merged from two
    # panels has one panel's uv, which says nothing about the other panel's threads.
    true = np.abs(length - rest) <= COLLINEAR * np.maximum(rest, 1e-12) * 1e3
    e, widths, span, length = e[true], widths[true], span[true], length[true]
    if len(e) == 0:
        return empty
    # Half-edges out of each node, with their direction.
    origin = np.concatenate([e[:, 0], e[:, 1]])
    target = np.concatenate([e[:, 1], e[:, 0]])
    direction = np.concatenate([span, -span]) / np.tile(length, 2)[:, None]
    hl = np.tile(length, 2)
    hw = np.tile(widths, 2)
    angle = np.arctan2(direction[:, 1], direction[:, 0])
    axis = np.mod(angle, np.pi)
    axis = np.where(axis > np.pi - 1e-9, 0.0, axis)
    key = np.round(axis / (COLLINEAR * 10.0)).astype(np.int64)
    forward = (np.abs(np.mod(angle, 2 * np.pi) - axis) < 1e-6).astype(np.int64)
    order = np.lexsort((forward, key, origin))
    origin, target, key, forward = origin[order], target[order], key[order], forward[order]
    hl, hw, direction = hl[order], hw[order], direction[order]
    # A backward half-edge followed by a forward one at the same node along the same axis.
    pair = (origin[:-1] == origin[1:]) & (key[:-1] == key[1:]) & (forward[:-1] == 0) & (forward[1:] == 1)
    back, ahead = np.flatnonzero(pair), np.flatnonzero(pair) + 1
    if len(back) == 0:
        return empty
    centre = origin[back]
    l1, l2 = hl[back], hl[ahead]
    weights = np.stack([2.0 / (l1 * (l1 + l2)), -2.0 / (l1 * l2), 2.0 / (l2 * (l1 + l2)), np.zeros_like(l1)], axis=1)
    scale = 0.5 * (hw[back] + hw[ahead]) * 0.5 * (l1 + l2)
    frame = _cross_neighbour(net, centre, direction[ahead])
    nodes = np.stack([target[back], centre, target[ahead], frame], axis=1)
    return nodes, weights, scale


def _cross_neighbour(net: ClothNet, centre: np.ndarray, along: np.ndarray) -> np.ndarray:
    """For each stencil centre, a neighbour off its thread (the centre itself if none): with
    the thread it spans the stencil's plane."""
    e = np.asarray(net.elements, np.int64)
    origin = np.concatenate([e[:, 0], e[:, 1]])
    target = np.concatenate([e[:, 1], e[:, 0]])
    order = np.argsort(origin, kind="stable")
    origin, target = origin[order], target[order]
    start = np.searchsorted(origin, centre, side="left")
    stop = np.searchsorted(origin, centre, side="right")
    out = centre.copy()
    best = np.zeros(len(centre))
    for slot in range(int((stop - start).max(initial=0))):
        has = start + slot < stop
        idx = np.where(has, start + slot, 0)
        other = target[idx]
        d = net.uv[other] - net.uv[centre]
        d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-30)
        off = np.abs(d[:, 0] * along[:, 1] - d[:, 1] * along[:, 0])
        better = has & (off > best + 1e-9)
        out = np.where(better, other, out)
        best = np.where(better, off, best)
    return out


def _twist_stencils(net: ClothNet):
    """Quads of the grid: two triangles sharing a diagonal, their four corners a rectangle."""
    empty = (np.zeros((0, 4), np.int64), np.zeros((0, 4)), np.zeros(0))
    tri = np.asarray(net.triangles, np.int64)
    if len(tri) == 0:
        return empty
    corner_uv = net.rest_triangle_uv()
    area = net.rest_triangle_areas()
    sides = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    owner = np.tile(np.arange(len(tri)), 3)
    slot = np.repeat(np.arange(3), len(tri))
    key = np.sort(sides, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    key, owner, slot = key[order], owner[order], slot[order]
    _, starts, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    first = starts[counts == 2]
    t0, t1 = owner[first], owner[first + 1]
    s0, s1 = slot[first], slot[first + 1]
    a = tri[t0, s0]
    b = tri[t0, (s0 + 1) % 3]
    c = tri[t0, (s0 + 2) % 3]
    d = tri[t1, (s1 + 2) % 3]
    # Rest positions from each triangle's own corners (a seam node has one uv per panel); the
    # two triangles must agree on the shared side.
    pa, pb, pc = corner_uv[t0, s0], corner_uv[t0, (s0 + 1) % 3], corner_uv[t0, (s0 + 2) % 3]
    pd = corner_uv[t1, (s1 + 2) % 3]
    a_first = (tri[t1, s1] == a)[:, None]
    qa = np.where(a_first, corner_uv[t1, s1], corner_uv[t1, (s1 + 1) % 3])
    qb = np.where(a_first, corner_uv[t1, (s1 + 1) % 3], corner_uv[t1, s1])
    quad = area[t0] + area[t1]
    tol = COLLINEAR * 1e3 * np.sqrt(np.maximum(quad, 1e-30))
    ca, da = pc - pa, pd - pa
    square = np.abs(np.sum(ca * da, axis=1)) <= COLLINEAR * 1e3 * np.linalg.norm(ca, axis=1) * np.linalg.norm(da, axis=1)
    ok = ((np.linalg.norm(pa + pb - pc - pd, axis=1) <= tol) & square & (quad > 0)
          & (np.linalg.norm(qa - pa, axis=1) <= tol) & (np.linalg.norm(qb - pb, axis=1) <= tol))
    nodes = np.stack([a, b, c, d], axis=1)[ok]
    w = 1.0 / quad[ok]
    weights = np.stack([w, w, -w, -w], axis=1)
    return nodes, weights, 2.0 * quad[ok]
