"""Untangling: layers of cloth that already pass through each other moved back through.

Collision response keeps a node on the side of a layer it started a step on, so it cannot undo
a crossing that is already there; sewing, whose panels pass through one another to reach their
partners (:mod:`party.garment.sewing`), can leave some where a panel folded through itself.
Intersection contour minimisation (Volino and Magnenat-Thalmann 2006, "Resolving surface
collisions through intersection contour minimization") moves the two surfaces of every
crossing relative to each other along the direction that shortens the curve they intersect
along, until the curve, and with it the crossing, is gone. Each edge that pierces a triangle
is one point of that curve; the edge's nodes are pushed along the gradient G there and the
triangle's against it.
"""

from __future__ import annotations

import numpy as np
import warp as wp

from ..device import resolve
from ..launch import launch
from ..meshing.net import triangle_edges
from .geometry import edge_pierces_triangle

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

STEP = 2.0e-4
"""Largest displacement of a node per iteration [m] (h0 of Volino's step)."""


@wp.func
def contour_gradient(x0: wp.vec3, x1: wp.vec3, opposite: wp.vec3, n: wp.vec3) -> wp.vec3:
    """Volino's G for edge x0-x1, one of whose faces has ``opposite`` as its third node,
    through a triangle of unit normal ``n``: the direction to move the edge's surface, relative
    to the triangle, that shortens their intersection curve. Unchanged when n flips."""
    e = wp.normalize(x1 - x0)
    m = wp.cross(x1 - x0, opposite - x0)
    r = wp.cross(n, m)
    if wp.length(r) < 1.0e-12:
        return wp.vec3(0.0)
    r = wp.normalize(r)
    inward = opposite - x0
    if wp.dot(r, inward - wp.dot(inward, e) * e) < 0.0:
        r = -r
    en = wp.dot(e, n)
    if wp.abs(en) < 1.0e-6:
        return r
    return r - 2.0 * wp.dot(e, r) / en * n


@wp.kernel
def contour_pushes(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), tris: wp.array(dtype=int, ndim=2),
                   edges: wp.array(dtype=wp.vec2i), opposite: wp.array(dtype=wp.vec2i),
                   push: wp.array(dtype=wp.vec3), count: wp.array(dtype=int)):
    """For each edge through a triangle: the unit gradient, averaged over the edge's faces
    (``opposite``: their third nodes, -1 where there is none), added to ``push`` at the edge's
    nodes and subtracted at the triangle's; ``count`` counts the crossings."""
    e = wp.tid()
    i = edges[e][0]
    k = edges[e][1]
    query = wp.mesh_query_aabb(mesh, wp.min(points[i], points[k]), wp.max(points[i], points[k]))
    t = int(0)
    while wp.mesh_query_aabb_next(query, t):
        if not edge_pierces_triangle(i, k, t, points, tris):
            continue
        wp.atomic_add(count, 0, 1)
        a = points[tris[t, 0]]
        n = wp.normalize(wp.cross(points[tris[t, 1]] - a, points[tris[t, 2]] - a))
        g = wp.vec3(0.0)
        for s in range(2):
            o = opposite[e][s]
            if o >= 0:
                g = g + contour_gradient(points[i], points[k], points[o], n)
        if wp.length(g) < 1.0e-12:
            continue
        g = wp.normalize(g)
        wp.atomic_add(push, i, g)
        wp.atomic_add(push, k, g)
        for c in range(3):
            wp.atomic_sub(push, tris[t, c], g)


@wp.kernel
def apply_pushes(points: wp.array(dtype=wp.vec3), push: wp.array(dtype=wp.vec3), free: wp.array(dtype=float),
                 step: float):
    """Move each free node by ``step`` [m] times P / sqrt(|P|^2 + 1) along its summed push P
    (Volino's bounded step, g0 = 1: one crossing moves a node by step / sqrt(2)); reset P."""
    i = wp.tid()
    p = push[i]
    if free[i] > 0.0:
        points[i] = points[i] + step * p / wp.sqrt(wp.dot(p, p) + 1.0)
    push[i] = wp.vec3(0.0)


def edge_opposites(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct edges of ``triangles`` (:func:`~party.meshing.net.triangle_edges`) and,
    per edge, the third nodes of up to two of its triangles (-1 where it has fewer), (e, 2)."""
    tris = np.asarray(triangles, np.int64)
    edges = triangle_edges(tris)
    sides = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    thirds = np.concatenate([tris[:, 2], tris[:, 0], tris[:, 1]])
    base = int(edges.max()) + 1
    edge_of_side = np.searchsorted(edges[:, 0] * base + edges[:, 1], sides[:, 0] * base + sides[:, 1])
    order = np.argsort(edge_of_side, kind="stable")
    ranked = edge_of_side[order]
    slot = np.arange(len(ranked)) - np.searchsorted(ranked, ranked)  # 0 for an edge's first face, 1 for its second
    keep = slot < 2
    opposite = -np.ones((len(edges), 2), dtype=np.int32)
    opposite[ranked[keep], slot[keep]] = thirds[order][keep]
    return edges, opposite


def untangle(points: np.ndarray, triangles: np.ndarray, free: np.ndarray | None = None, *,
             iterations: int = 400, step: float = STEP, device: str | None = None) -> tuple[np.ndarray, int]:
    """Move ``points`` [m] of the cloth ``triangles`` until no edge passes through a
    triangle, or for ``iterations``; nodes not ``free`` (a boolean per node) stay. Returns the
    points and the crossings left (``party.output.metrics.cloth_crossings`` counts the same)."""
    if len(triangles) == 0:
        return points, 0
    device = resolve(device)
    edges, opposite = edge_opposites(triangles)
    start = np.asarray(points, np.float32)
    pts = wp.array(start, dtype=wp.vec3, device=device)
    tris = wp.array(np.asarray(triangles, np.int32), dtype=int, device=device)
    mesh = wp.Mesh(points=pts, indices=wp.array(np.asarray(triangles, np.int32).ravel(), dtype=int, device=device))
    edge_array = wp.array(edges.astype(np.int32), dtype=wp.vec2i, device=device)
    opposite_array = wp.array(opposite, dtype=wp.vec2i, device=device)
    movable = np.ones(len(points)) if free is None else np.asarray(free, float)
    free_array = wp.array(movable.astype(np.float32), dtype=float, device=device)
    push = wp.zeros(len(points), dtype=wp.vec3, device=device)
    count = wp.zeros(1, dtype=int, device=device)
    for iteration in range(iterations + 1):
        mesh.refit()
        count.zero_()
        launch(contour_pushes, dim=len(edges), inputs=[mesh.id, pts, tris, edge_array, opposite_array, push, count],
               device=device)
        left = int(count.numpy()[0])
        if left == 0 or iteration == iterations:
            break
        launch(apply_pushes, dim=len(points), inputs=[pts, push, free_array, step], device=device)
    return np.asarray(points, np.float64) + (pts.numpy() - start), left
