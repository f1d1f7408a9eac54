"""A last line of defence against cloth passing through cloth.

The paper's cloth-cloth detection (section 6.3) tests each node against triangles along its
step; two edges can still pass through each other between nodes, more so over a large step.
After a step, the guard looks for mesh edges that pass through a triangle (sharing no node)
at the end of the step but did not at its start, and sends the nodes of each such pair back
to where the step began, at rest (or, checking every few steps, to where the last check left
them). It checks every edge: checking only edges with a node whose
collision search had found cloth triangles along its step saved some 15 % of a self-colliding
step, but let an edge longer than the search's reach pass through a triangle unseen
(GarmentCode's hoody draped with the implicit solver: 2 crossings). It repeats until no new
crossing is left: at worst every node is back at its start, which had none, so no step ever
creates a crossing. A repeat rechecks only the edges whose answer the revert can have changed
(:meth:`CrossingGuard._recheck`). Crossings present before a step (from a set-up) are left
alone and not counted as new.
"""

from __future__ import annotations

import numpy as np
import warp as wp

from ..launch import launch_items
from ..model import Model
from ..meshing.net import triangle_edges
from .geometry import edge_pierces_triangle

MAX_SPREAD = 32
"""Rounds of growing the reverted nodes over stretched elements (:meth:`CrossingGuard._spread`)."""

MAX_ROUNDS = 16
"""Rounds of check-and-revert per step; a round reverts every pair found, so a step needs
more than a few only when many layers pile up at once."""


@wp.kernel
def _check_edges(first: int, mesh: wp.uint64, points: wp.array(dtype=wp.vec3), tris: wp.array(dtype=int, ndim=2),
                 edges: wp.array(dtype=wp.vec2i), dirty: wp.array(dtype=int), everything: int,
                 crossed_before: wp.array(dtype=int), crossed_now: wp.array(dtype=int), revert: wp.array(dtype=int),
                 found: wp.array(dtype=int)):
    """Mark the edges through a triangle now (all of them, or with ``everything`` 0 only the
    ``dirty`` ones); for those that were not at the last check, set ``found`` and mark the
    edge's and triangle's nodes to revert (flags only: item-wise, see :mod:`party.launch`)."""
    e = first + wp.tid()
    if everything == 0 and dirty[e] == 0:
        return
    i = edges[e][0]
    k = edges[e][1]
    crossed_now[e] = 0
    query = wp.mesh_query_aabb(mesh, wp.min(points[i], points[k]), wp.max(points[i], points[k]))
    t = int(0)
    while wp.mesh_query_aabb_next(query, t):
        if edge_pierces_triangle(i, k, t, points, tris):
            crossed_now[e] = 1
            if crossed_before[e] == 0:
                found[0] = 1
                revert[i] = 1
                revert[k] = 1
                revert[tris[t, 0]] = 1
                revert[tris[t, 1]] = 1
                revert[tris[t, 2]] = 1


@wp.kernel
def _spread_revert(elem_nodes: wp.array(dtype=wp.vec2i), max_length: wp.array(dtype=float),
                   inv_mass: wp.array(dtype=float), anchor: wp.array(dtype=wp.vec3), x: wp.array(dtype=wp.vec3),
                   revert: wp.array(dtype=int), added: wp.array(dtype=int)):
    """Mark for reverting the free end of an element whose other end goes back, where the two
    would otherwise end farther apart than the element's plastic limit allows."""
    pair = elem_nodes[wp.tid()]
    i = pair[0]
    k = pair[1]
    ri = revert[i] != 0 and inv_mass[i] > 0.0
    rk = revert[k] != 0 and inv_mass[k] > 0.0
    if ri == rk:
        return
    pi = x[i]
    pk = x[k]
    if ri:
        pi = anchor[i]
    else:
        pk = anchor[k]
    if wp.length(pk - pi) > max_length[wp.tid()]:
        if ri:
            revert[k] = 1
        else:
            revert[i] = 1
        wp.atomic_add(added, 0, 1)


@wp.kernel
def _revert(x_start: wp.array(dtype=wp.vec3), inv_mass: wp.array(dtype=float), revert: wp.array(dtype=int),
            x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), reverted: wp.array(dtype=int),
            moved: wp.array(dtype=int)):
    i = wp.tid()
    moved[i] = 0
    if revert[i] != 0 and inv_mass[i] > 0.0:
        x[i] = x_start[i]
        v[i] = wp.vec3(0.0)
        reverted[i] = 1
        moved[i] = 1
    revert[i] = 0


@wp.kernel
def _edge_boxes(first: int, points: wp.array(dtype=wp.vec3), edges: wp.array(dtype=wp.vec2i),
                moved: wp.array(dtype=int), lower: wp.array(dtype=wp.vec3), upper: wp.array(dtype=wp.vec3),
                dirty: wp.array(dtype=int)):
    """Each edge's box, and whether one of its nodes has just moved back."""
    e = first + wp.tid()
    i = edges[e][0]
    k = edges[e][1]
    lower[e] = wp.min(points[i], points[k])
    upper[e] = wp.max(points[i], points[k])
    dirty[e] = wp.where(moved[i] != 0 or moved[k] != 0, 1, 0)


@wp.kernel
def _edges_near_moved_triangles(first: int, edge_tree: wp.uint64, before: wp.array(dtype=wp.vec3),
                                points: wp.array(dtype=wp.vec3), tris: wp.array(dtype=int, ndim=2),
                                moved: wp.array(dtype=int), dirty: wp.array(dtype=int)):
    """Mark dirty the edges whose box meets a triangle that has a node just moved back, where
    it was ``before`` or where it is now: they may now cross it, or no longer (flags only)."""
    t = first + wp.tid()
    a = tris[t, 0]
    b = tris[t, 1]
    c = tris[t, 2]
    if moved[a] == 0 and moved[b] == 0 and moved[c] == 0:
        return
    lo = wp.min(wp.min(points[a], wp.min(points[b], points[c])), wp.min(before[a], wp.min(before[b], before[c])))
    hi = wp.max(wp.max(points[a], wp.max(points[b], points[c])), wp.max(before[a], wp.max(before[b], before[c])))
    query = wp.bvh_query_aabb(edge_tree, lo, hi)
    e = int(0)
    while wp.bvh_query_next(query, e):
        dirty[e] = 1


class CrossingGuard:
    """Checks each step's end (or every ``every``-th step's) for new edge-through-triangle
    crossings and reverts their nodes to where the last check left them.

    Checking every few small steps of the explicit solver, rather than every step, costs a
    fraction and guards the same: nodes reverted go back a few steps (a millimetre or so at
    the explicit solver's steps) to a state that had no new crossing."""

    def __init__(self, model: Model, every: int = 1) -> None:
        self.model = model
        self.every = max(int(every), 1)
        dev = model.device
        tri = model.triangles
        edges = triangle_edges(tri)
        self.edge_count = len(edges)
        self.edges = wp.array(edges.astype(np.int32), dtype=wp.vec2i, device=dev)
        self.points = wp.clone(model.node_rest_points)
        self.mesh = wp.Mesh(points=self.points, indices=wp.array(tri.ravel().astype(np.int32), dtype=int, device=dev))
        self.crossed_before = wp.zeros(self.edge_count, dtype=int, device=dev)
        self.crossed_now = wp.zeros(self.edge_count, dtype=int, device=dev)
        self.revert = wp.zeros(model.node_count, dtype=int, device=dev)
        self.reverted = wp.zeros(model.node_count, dtype=int, device=dev)
        self.found = wp.zeros(1, dtype=int, device=dev)
        self.anchor = wp.zeros(model.node_count, dtype=wp.vec3, device=dev)
        self.added = wp.zeros(1, dtype=int, device=dev)
        self.moved = wp.zeros(model.node_count, dtype=int, device=dev)
        self.dirty = wp.zeros(self.edge_count, dtype=int, device=dev)
        self._edge_lower = wp.zeros(self.edge_count, dtype=wp.vec3, device=dev)
        self._edge_upper = wp.zeros(self.edge_count, dtype=wp.vec3, device=dev)
        self._edge_tree: wp.Bvh | None = None
        self._limited = bool(np.isfinite(model.element_max_length.numpy()).any())
        self.reverts = 0
        self.pending = 0
        self._primed = False

    def prime(self, x: wp.array) -> None:
        """Record which edges cross at ``x`` (the state before the first step)."""
        self._check(x)
        wp.copy(self.crossed_before, self.crossed_now)
        wp.copy(self.anchor, x)
        self._primed = True

    def apply(self, x_start: wp.array, x: wp.array, v: wp.array) -> int:
        """After a step from ``x_start``: on every ``every``-th step, :meth:`check` ``x`` and
        ``v``; returns the number of nodes reverted."""
        if not self._primed:
            self.prime(x_start)
        self.pending += 1
        return self.check(x, v) if self.pending >= self.every else 0

    def check(self, x: wp.array, v: wp.array) -> int:
        """Revert the nodes of crossings new since the last check (``x``, ``v`` in place) to
        where that check left them, at rest; returns the number of nodes reverted (syncs with
        the device)."""
        m = self.model
        self.pending = 0
        self.reverted.zero_()
        any_new = False
        for attempt in range(MAX_ROUNDS):
            if not (self._check(x) if attempt == 0 else self._recheck(x)):
                break
            any_new = True
            self._spread(x)
            wp.launch(_revert, dim=m.node_count,
                      inputs=[self.anchor, m.node_inv_mass, self.revert, x, v, self.reverted, self.moved], device=m.device)
        wp.copy(self.crossed_before, self.crossed_now)
        wp.copy(self.anchor, x)
        count = int(self.reverted.numpy().sum()) if any_new else 0
        self.reverts += count
        return count

    def _spread(self, x: wp.array) -> None:
        """Grow the nodes to revert until none leaves an element stretched beyond its plastic
        limit (a node going back a large step, or several small ones, would otherwise leave its
        neighbours' elements stretched by as far as they moved meanwhile: 21 % beyond rest in
        the dress demo, checked every 33 steps)."""
        m = self.model
        if not self._limited:
            return
        for _ in range(MAX_SPREAD):
            self.added.zero_()
            wp.launch(_spread_revert, dim=m.element_count,
                      inputs=[m.element_nodes, m.element_max_length, m.node_inv_mass, self.anchor, x, self.revert,
                              self.added], device=m.device)
            if int(self.added.numpy()[0]) == 0:
                break

    def _check(self, x: wp.array, everything: bool = True) -> bool:
        """Whether ``x`` has an edge through a triangle that the last check did not have
        (checking every edge, or only the dirty ones)."""
        m = self.model
        wp.copy(self.points, x)
        self.mesh.refit()
        self.found.zero_()
        launch_items(_check_edges, 0, self.edge_count,
                     [self.mesh.id, self.points, m.triangle_nodes, self.edges, self.dirty, int(everything),
                      self.crossed_before, self.crossed_now, self.revert, self.found], m.device)
        return bool(self.found.numpy()[0])

    def _recheck(self, x: wp.array) -> bool:
        """:meth:`_check` after a revert, of only the edges whose answer it can have changed:
        those with a node that moved back and those near a triangle with one, where it was or
        where it is now (found with a BVH over the edges' boxes; ``self.points`` still holds the
        last round's positions); every other edge and every triangle near it stayed where the
        last round checked them. (On the reference dress's implicit drape, which rechecks
        after four steps of five, checking cost 14 s of kernel time summed over both threads
        with every edge rechecked, 8 s with these.)"""
        m = self.model
        launch_items(_edge_boxes, 0, self.edge_count,
                     [x, self.edges, self.moved, self._edge_lower, self._edge_upper, self.dirty], m.device)
        if self._edge_tree is None:
            self._edge_tree = wp.Bvh(self._edge_lower, self._edge_upper)
        else:
            self._edge_tree.refit()
        launch_items(_edges_near_moved_triangles, 0, m.triangle_count,
                     [self._edge_tree.id, self.points, x, m.triangle_nodes, self.moved, self.dirty], m.device)
        return self._check(x, everything=False)
