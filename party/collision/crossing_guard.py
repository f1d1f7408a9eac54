"""A last line of defence against cloth passing through cloth.

The paper's cloth-cloth detection (section 6.3) tests each node against triangles along its
step; two edges can still pass through each other between nodes, more so over a large step.
After a step, the guard looks for mesh edges that pass through a triangle (sharing no node)
at the end of the step but did not at its start, and sends the nodes of each such pair back
to where the step began, at rest (or, checking every few steps, to where the last check left
them). It checks every edge, not only those whose nodes' collision search found cloth along
their step: an edge longer than the search's reach can pass through a triangle that no node of
it came near. It repeats until no new
crossing is left: at worst every node is back at its start, which had none, so no step ever
creates a crossing. Crossings present before a step (from a set-up) are left alone and not
counted as new.

Each check tests every edge against the triangles listed near it, not against a fresh search: a
search lists, per edge, the triangles within a reach of it (``near_reach``; a Verlet list).
No other triangle can have come to an edge before one of their nodes has moved half the reach
since, beyond the mean displacement of all nodes (a common translation moves no pair closer: cloth
falling as a whole keeps its lists); the edges and triangles at such nodes are searched with BVHs
at every check, and the lists are made anew once too many nodes have (``hot_share``; both in
:class:`GuardSettings`). Searching every edge at every check would cost a large share of a
drape's step (:meth:`CrossingGuard._check`). Where the cloth moves so fast that lists would
be made again within a few checks (a sheet striking a sphere at large steps), each edge is
tested against the triangles its box meets, unlisted: that search finds no more than a listing
does and costs less than half of one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import warp as wp

from ..launch import launch, launch_items
from ..model import Model
from ..meshing.net import triangle_edges
from .geometry import edge_pierces_triangle, edge_shares_node, segment_hits_triangle, segment_triangle_distance

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

MAX_SPREAD = 32
"""Rounds of growing the reverted nodes over stretched elements (:meth:`CrossingGuard._spread`)."""

@dataclass(frozen=True)
class GuardSettings:
    """How the crossing guard searches (any of these gives the same answer, at another cost).

    Attributes:
        near_reach: How far [m] from an edge the triangles listed for it reach, at most; and at
            most half the net's median edge, so that a flat sheet's own triangles beyond the
            edge's ring are not listed.
        near_room: Triangles listed per edge at first; the lists grow when a search finds more.
        hot_share: The lists are made again once more than this share of the nodes (and at
            least 8) have moved half the reach since they were listed; until then the edges and
            triangles at those nodes are searched at every check.
        fast_share: A list would be made again within a few checks where, since the last check,
            more nodes than ``hot_share`` allows moved farther than this share of the reach
            (beyond the mean displacement); the check then tests every edge against the
            triangles its box meets, without listing (about 40 % of a listing's cost).
        keep_lists: Keep the lists from check to check (False: list anew at every check).
        partial_recheck: After a round of reverts test only what the reverted nodes touch
            (False: test every pair again).
    """

    near_reach: float = 8.0e-3
    near_room: int = 16
    hot_share: float = 0.1
    fast_share: float = 0.25
    keep_lists: bool = True
    partial_recheck: bool = True


MAX_ROUNDS = 16
"""Rounds of check-and-revert per step; a round reverts every pair found, so a step needs
more than a few only when many layers pile up at once."""


@wp.func
def _mark_crossing(e: int, i: int, k: int, t: int, tris: wp.array(dtype=int, ndim=2),
                   crossed_before: wp.array(dtype=int), crossed_now: wp.array(dtype=int),
                   revert: wp.array(dtype=int), found: wp.array(dtype=int)):
    """Edge e (nodes i, k) passes through triangle t now: mark it, and where it did not at the
    last check, set ``found`` and mark the edge's and triangle's nodes to revert."""
    crossed_now[e] = 1
    if crossed_before[e] == 0:
        found[0] = 1
        revert[i] = 1
        revert[k] = 1
        revert[tris[t, 0]] = 1
        revert[tris[t, 1]] = 1
        revert[tris[t, 2]] = 1


@wp.func
def _mark_through_box(e: int, i: int, k: int, mesh: wp.uint64, points: wp.array(dtype=wp.vec3),
                      tris: wp.array(dtype=int, ndim=2), crossed_before: wp.array(dtype=int),
                      crossed_now: wp.array(dtype=int), revert: wp.array(dtype=int), found: wp.array(dtype=int)):
    """Test edge e (nodes i, k) against every triangle its box meets (``mesh`` refit at
    ``points``) and mark it where it passes through one (:func:`_mark_crossing`)."""
    query = wp.mesh_query_aabb(mesh, wp.min(points[i], points[k]), wp.max(points[i], points[k]))
    t = int(0)
    while wp.mesh_query_aabb_next(query, t):
        if edge_pierces_triangle(i, k, t, points, tris):
            _mark_crossing(e, i, k, t, tris, crossed_before, crossed_now, revert, found)


@wp.kernel
def _list_and_check_edges(first: int, mesh: wp.uint64, points: wp.array(dtype=wp.vec3),
                          tris: wp.array(dtype=int, ndim=2), edges: wp.array(dtype=wp.vec2i), reach: float,
                          near: wp.array(dtype=int, ndim=2), near_count: wp.array(dtype=int),
                          crossed_before: wp.array(dtype=int), crossed_now: wp.array(dtype=int),
                          revert: wp.array(dtype=int), found: wp.array(dtype=int), overflow: wp.array(dtype=int)):
    """List the triangles sharing no node with edge e that come within ``reach`` of it
    (``near_count`` counts all of them, beyond the room too; ``overflow`` is set then),
    and mark the edge where it passes through one of them (flags only: item-wise, see
    :mod:`party.launch`)."""
    e = first + wp.tid()
    i = edges[e][0]
    k = edges[e][1]
    crossed_now[e] = 0
    room = near.shape[1]
    query = wp.mesh_query_aabb(mesh, wp.min(points[i], points[k]) - wp.vec3(reach),
                               wp.max(points[i], points[k]) + wp.vec3(reach))
    t = int(0)
    count = int(0)
    while wp.mesh_query_aabb_next(query, t):
        a = tris[t, 0]
        b = tris[t, 1]
        c = tris[t, 2]
        if edge_shares_node(i, k, t, tris):
            continue
        distance = segment_triangle_distance(points[i], points[k], points[a], points[b], points[c])
        if distance > reach:
            continue
        if count < room:
            near[e, count] = t
        else:
            overflow[0] = 1
        count += 1
        # the distance is zero where the edge passes through (and where it only touches)
        if distance == 0.0 and segment_hits_triangle(points[i], points[k], points[a], points[b], points[c]):
            _mark_crossing(e, i, k, t, tris, crossed_before, crossed_now, revert, found)
    near_count[e] = count


@wp.kernel
def _check_listed_edges(first: int, mesh: wp.uint64, points: wp.array(dtype=wp.vec3),
                        tris: wp.array(dtype=int, ndim=2), edges: wp.array(dtype=wp.vec2i),
                        near: wp.array(dtype=int, ndim=2), near_count: wp.array(dtype=int),
                        hot: wp.array(dtype=int), crossed_before: wp.array(dtype=int),
                        crossed_now: wp.array(dtype=int), revert: wp.array(dtype=int), found: wp.array(dtype=int)):
    """Mark edge e where it passes through one of the triangles listed for it; an edge with a
    ``hot`` node (moved beyond half the reach since the listing) is tested against every
    triangle its box meets instead (``mesh`` refit at ``points``; flags only)."""
    e = first + wp.tid()
    i = edges[e][0]
    k = edges[e][1]
    crossed_now[e] = 0
    if hot[i] != 0 or hot[k] != 0:
        _mark_through_box(e, i, k, mesh, points, tris, crossed_before, crossed_now, revert, found)
        return
    for j in range(wp.min(near_count[e], near.shape[1])):
        t = near[e, j]
        if segment_hits_triangle(points[i], points[k], points[tris[t, 0]], points[tris[t, 1]], points[tris[t, 2]]):
            _mark_crossing(e, i, k, t, tris, crossed_before, crossed_now, revert, found)


@wp.kernel
def _recheck_edges(first: int, mesh: wp.uint64, points: wp.array(dtype=wp.vec3), tris: wp.array(dtype=int, ndim=2),
                   edges: wp.array(dtype=wp.vec2i), changed: wp.array(dtype=int), crossed_before: wp.array(dtype=int),
                   crossed_now: wp.array(dtype=int), revert: wp.array(dtype=int), found: wp.array(dtype=int)):
    """After a round of reverts: test edge e against every triangle its box meets (``mesh``
    refit at ``points``) where a node of it was ``changed`` (reverted) or it was marked in the
    last round; any other edge keeps its mark, 0 (flags only)."""
    e = first + wp.tid()
    i = edges[e][0]
    k = edges[e][1]
    if changed[i] == 0 and changed[k] == 0 and crossed_now[e] == 0:
        return
    crossed_now[e] = 0
    _mark_through_box(e, i, k, mesh, points, tris, crossed_before, crossed_now, revert, found)


@wp.kernel
def _check_hot_triangles(first: int, edge_tree: wp.uint64, points: wp.array(dtype=wp.vec3),
                         tris: wp.array(dtype=int, ndim=2), edges: wp.array(dtype=wp.vec2i),
                         hot: wp.array(dtype=int), crossed_before: wp.array(dtype=int),
                         crossed_now: wp.array(dtype=int), revert: wp.array(dtype=int), found: wp.array(dtype=int)):
    """For triangle t with a ``hot`` node: mark the edges without one (those with one test every
    triangle themselves) that pass through it, found with a BVH over the edges' boxes at
    ``points`` (flags only: an edge's mark is only ever set here)."""
    t = first + wp.tid()
    a = tris[t, 0]
    b = tris[t, 1]
    c = tris[t, 2]
    if hot[a] == 0 and hot[b] == 0 and hot[c] == 0:
        return
    query = wp.bvh_query_aabb(edge_tree, wp.min(points[a], wp.min(points[b], points[c])),
                              wp.max(points[a], wp.max(points[b], points[c])))
    e = int(0)
    while wp.bvh_query_next(query, e):
        i = edges[e][0]
        k = edges[e][1]
        if hot[i] == 0 and hot[k] == 0 and edge_pierces_triangle(i, k, t, points, tris):
            _mark_crossing(e, i, k, t, tris, crossed_before, crossed_now, revert, found)


@wp.kernel
def _sum_displacement(points: wp.array(dtype=wp.vec3), listed_at: wp.array(dtype=wp.vec3),
                      total: wp.array(dtype=wp.vec3)):
    """Sum the nodes' displacements [m] since the lists were made into ``total[0]``."""
    i = wp.tid()
    wp.atomic_add(total, 0, points[i] - listed_at[i])


@wp.kernel
def _mark_hot(points: wp.array(dtype=wp.vec3), listed_at: wp.array(dtype=wp.vec3), total: wp.array(dtype=wp.vec3),
              share: float, limit: float, hot: wp.array(dtype=int), count: wp.array(dtype=int)):
    """Mark the nodes that moved farther than ``limit`` [m], beyond the mean displacement
    (``share`` times ``total[0]``), since the lists were made, and count them."""
    i = wp.tid()
    hot[i] = 0
    if wp.length(points[i] - listed_at[i] - share * total[0]) > limit:
        hot[i] = 1
        wp.atomic_add(count, 0, 1)


@wp.kernel
def _edge_boxes(points: wp.array(dtype=wp.vec3), edges: wp.array(dtype=wp.vec2i), lower: wp.array(dtype=wp.vec3),
                upper: wp.array(dtype=wp.vec3)):
    e = wp.tid()
    lower[e] = wp.min(points[edges[e][0]], points[edges[e][1]])
    upper[e] = wp.max(points[edges[e][0]], points[edges[e][1]])


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
            changed: wp.array(dtype=int)):
    """Send the free nodes marked in ``revert`` back to ``x_start``, at rest; mark them in
    ``reverted`` (every round of a check) and in ``changed`` (this round only)."""
    i = wp.tid()
    changed[i] = 0
    if revert[i] != 0 and inv_mass[i] > 0.0:
        x[i] = x_start[i]
        v[i] = wp.vec3(0.0)
        reverted[i] = 1
        changed[i] = 1
    revert[i] = 0


class CrossingGuard:
    """Checks each step's end (or every ``every``-th step's) for new edge-through-triangle
    crossings and reverts their nodes to where the last check left them.

    Checking every few small steps of the explicit solver, rather than every step, costs a
    fraction and guards the same: nodes reverted go back a few steps (a millimetre or so at
    the explicit solver's steps) to a state that had no new crossing."""

    def __init__(self, model: Model, every: int = 1, settings: GuardSettings = GuardSettings()) -> None:
        self.model = model
        self.every = max(int(every), 1)
        self.settings = settings
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
        self.changed = wp.zeros(model.node_count, dtype=int, device=dev)
        self.found = wp.zeros(1, dtype=int, device=dev)
        self.anchor = wp.zeros(model.node_count, dtype=wp.vec3, device=dev)
        self.added = wp.zeros(1, dtype=int, device=dev)
        self.near = wp.zeros((self.edge_count, settings.near_room), dtype=int, device=dev)
        self.near_count = wp.zeros(self.edge_count, dtype=int, device=dev)
        self.listed_at = wp.zeros(model.node_count, dtype=wp.vec3, device=dev)
        rest = model.host.element_rest_length
        self.reach = min(settings.near_reach, 0.5 * float(np.median(rest))) if len(rest) else settings.near_reach
        self._listed = False
        self._flag = wp.zeros(1, dtype=int, device=dev)
        self.hot = wp.zeros(model.node_count, dtype=int, device=dev)
        self._displacement = wp.zeros(1, dtype=wp.vec3, device=dev)
        self._most_hot = max(8, int(settings.hot_share * model.node_count))
        self._everywhere = wp.ones(model.node_count, dtype=int, device=dev)
        self._edge_lower = wp.zeros(self.edge_count, dtype=wp.vec3, device=dev)
        self._edge_upper = wp.zeros(self.edge_count, dtype=wp.vec3, device=dev)
        self._edge_tree: wp.Bvh | None = None
        self.searches = 0
        self.rechecks = 0
        self.direct_checks = 0
        self._limited = bool(np.isfinite(model.element_max_length.numpy()).any())
        self.reverts = 0
        self.pending = 0
        self._primed = False

    carried = ("crossed_before", "anchor", "pending", "_primed")
    """What the next check reads of the last (:mod:`party.solvers.memory`): the edges crossing
    then, where the nodes were, and the steps since."""

    def forget_search(self) -> None:
        """Drop the edge tree and the edges' lists, made anew at the next check
        (:func:`party.solvers.memory.forget`: the tree's shape depends on the boxes it was
        first built from, the lists' room on what they once had to hold)."""
        self._edge_tree = None
        self._listed = False
        self.near = wp.zeros((self.edge_count, self.settings.near_room), dtype=int, device=self.model.device)

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
        for round_ in range(MAX_ROUNDS):
            if not (self._recheck(x) if round_ and self.settings.partial_recheck else self._check(x)):
                break
            any_new = True
            self._spread(x)
            launch(_revert, dim=m.node_count,
                   inputs=[self.anchor, m.node_inv_mass, self.revert, x, v, self.reverted, self.changed],
                   device=m.device)
        wp.copy(self.crossed_before, self.crossed_now)
        wp.copy(self.anchor, x)
        count = int(self.reverted.numpy().sum()) if any_new else 0
        self.reverts += count
        return count

    def _spread(self, x: wp.array) -> None:
        """Grow the nodes to revert until none leaves an element stretched beyond its plastic
        limit (a node going back a large step, or several small ones, would otherwise leave its
        neighbours' elements stretched by as far as they moved meanwhile, well beyond the
        limit where the guard checks every few steps)."""
        m = self.model
        if not self._limited:
            return
        for _ in range(MAX_SPREAD):
            self.added.zero_()
            launch(_spread_revert, dim=m.element_count,
                   inputs=[m.element_nodes, m.element_max_length, m.node_inv_mass, self.anchor, x, self.revert,
                           self.added], device=m.device)
            if int(self.added.numpy()[0]) == 0:
                break

    def _check(self, x: wp.array) -> bool:
        """Whether ``x`` has an edge through a triangle that the last check did not have. Each
        edge is tested against the triangles listed for it, except where a node has moved half
        the reach since the listing, beyond the mean displacement of all nodes (a hot node): an
        edge with a hot node is tested against every triangle its box meets, and a triangle
        with a hot node against every edge whose box meets it. No other pair can have come
        together since the listing (the distance between two points changed by no more than
        the sum of their displacements beyond any common one, each less than half the reach),
        so the answer is that of testing every pair, to the bit. The lists are made anew once
        too many nodes are hot."""
        m = self.model
        self.found.zero_()
        hot = 0
        if not self.settings.keep_lists:
            self._listed = False
        if self._listed:
            hot = self._mark_moved(x, self.listed_at, 0.5 * self.reach)
            self._listed = hot <= self._most_hot
        if not self._listed:
            if self._moving_fast(x):
                self._check_every_edge(x)
            else:
                self._list_and_check(x)
            return bool(self.found.numpy()[0])
        if hot:
            self._refit_mesh(x)
            self._refit_edge_tree(x)
        launch_items(_check_listed_edges, 0, self.edge_count,
                     [self.mesh.id, x, m.triangle_nodes, self.edges, self.near, self.near_count, self.hot,
                      self.crossed_before, self.crossed_now, self.revert, self.found], m.device)
        if hot:
            launch_items(_check_hot_triangles, 0, m.triangle_count,
                         [self._edge_tree.id, x, m.triangle_nodes, self.edges, self.hot, self.crossed_before,
                          self.crossed_now, self.revert, self.found], m.device)
        return bool(self.found.numpy()[0])

    def _recheck(self, x: wp.array) -> bool:
        """:meth:`_check` after a round of reverts, which moved only the nodes marked in
        ``changed``: the edges at those nodes (and those marked in the last round) are tested
        against every triangle their box meets, the triangles at those nodes against every
        edge whose box meets them, and every other pair is as the last round found it. The
        same answer as checking every pair again, to the bit, for the few nodes a round moves:
        a garment at rest may have reverts in most steps, and a full check per round would cost
        each round as much as the first."""
        m = self.model
        self.rechecks += 1
        self.found.zero_()
        self._refit_mesh(x)
        self._refit_edge_tree(x)
        launch_items(_recheck_edges, 0, self.edge_count,
                     [self.mesh.id, x, m.triangle_nodes, self.edges, self.changed, self.crossed_before,
                      self.crossed_now, self.revert, self.found], m.device)
        launch_items(_check_hot_triangles, 0, m.triangle_count,
                     [self._edge_tree.id, x, m.triangle_nodes, self.edges, self.changed, self.crossed_before,
                      self.crossed_now, self.revert, self.found], m.device)
        return bool(self.found.numpy()[0])

    def _refit_edge_tree(self, x: wp.array) -> None:
        """Move the BVH over the edges' boxes to ``x`` (made on first use)."""
        launch(_edge_boxes, dim=self.edge_count, inputs=[x, self.edges, self._edge_lower, self._edge_upper],
               device=self.model.device)
        if self._edge_tree is None:
            self._edge_tree = wp.Bvh(self._edge_lower, self._edge_upper)
        else:
            self._edge_tree.refit()

    def _moving_fast(self, x: wp.array) -> bool:
        """Whether more nodes than ``hot_share`` allows moved farther than ``fast_share`` of the
        reach, beyond the mean displacement, since the last check:
        a list made now would be made again within a few checks."""
        return self._mark_moved(x, self.anchor, self.settings.fast_share * self.reach) > self._most_hot

    def _mark_moved(self, x: wp.array, since: wp.array, limit: float) -> int:
        """Mark in ``hot`` the nodes that moved farther than ``limit`` [m] from ``since``, beyond
        the mean displacement of all nodes, and count them (syncs with the device)."""
        m = self.model
        self._flag.zero_()
        self._displacement.zero_()
        launch(_sum_displacement, dim=m.node_count, inputs=[x, since, self._displacement], device=m.device)
        launch(_mark_hot, dim=m.node_count,
               inputs=[x, since, self._displacement, 1.0 / m.node_count, limit, self.hot, self._flag],
               device=m.device)
        return int(self._flag.numpy()[0])

    def _refit_mesh(self, x: wp.array) -> None:
        """Move the triangles' mesh (and its BVH) to ``x``."""
        wp.copy(self.points, x)
        self.mesh.refit()

    def _check_every_edge(self, x: wp.array) -> None:
        """Mark the edges through a triangle at ``x``, each tested against every triangle its
        box meets (no lists are made)."""
        m = self.model
        self.direct_checks += 1
        self._refit_mesh(x)
        launch_items(_check_listed_edges, 0, self.edge_count,
                     [self.mesh.id, x, m.triangle_nodes, self.edges, self.near, self.near_count, self._everywhere,
                      self.crossed_before, self.crossed_now, self.revert, self.found], m.device)

    def _list_and_check(self, x: wp.array) -> None:
        """List each edge's triangles at ``x`` (with room for all of them: the lists grow where
        a search finds more than they hold) and mark the edges through one."""
        m = self.model
        self.searches += 1
        self._refit_mesh(x)
        while True:
            self._flag.zero_()
            launch_items(_list_and_check_edges, 0, self.edge_count,
                         [self.mesh.id, self.points, m.triangle_nodes, self.edges, self.reach, self.near,
                          self.near_count, self.crossed_before, self.crossed_now, self.revert, self.found,
                          self._flag], m.device)
            if not int(self._flag.numpy()[0]):
                break
            room = int(self.near_count.numpy().max())
            self.near = wp.zeros((self.edge_count, room), dtype=int, device=m.device)
        wp.copy(self.listed_at, x)
        self.hot.zero_()
        self._listed = True
