"""The Collision() of eq. (5): body and cloth responses chained through layers (figure 10)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import warp as wp

from ..launch import launch, launch_items
from ..model import Model, State
from ..model.csr import csr_order
from ..errors import InvalidInput, SimulationUnstable
from .body import MAX_FACES, collide_body, gather_body_faces, gather_body_faces_bvh
from .body_vertices import (MAX_VERTICES, gather_body_vertices, respond_body_vertices, vertex_boxes,
                            vertices_to_test)
from .bvh import TriangleBvh
from .crossing_guard import GuardSettings
from .cloth import (MAX_CANDIDATES, MAX_CONTACTS, apply_cloth_response, detect_cloth, gather_cloth_triangles,
                    gather_cloth_triangles_bvh, moved_beyond, respond_cloth, searched_velocity, sum_motion)
from .intervals import AxisIntervalLists
from .landing import LANDING_REACH, MAX_LANDING_SUBSTEPS, landing_substeps, largest_speed, shortest_edge

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels


CLOTH_MARGIN_PER_ELEMENT = 0.25
"""The cloth search's margin, as a share of the net's median element, where ``search_margin``
would list the net's own layer (:meth:`CollisionPipeline.default_cloth_margin`). A search lists
the triangles within eps plus its margin; in a net finer than that reach it would list the
node's own flat ring, which no fold can bring into contact but every detection would test. A
quarter of an element keeps the ring out and still leaves the half-margin a node may move
before a search is repeated larger than most steps."""

OWN_LAYER_LISTED = 0.5
"""Cloth triangles a node that ``search_margin`` may add to the set-up positions' listing before
the cloth's margin narrows (:data:`CLOTH_MARGIN_PER_ELEMENT`). A narrower margin means more
searches, so a net that lists almost none of its own layer keeps the widest; one listing half a
triangle a node or more pays for its own ring at every detection, more than the extra searches
cost."""


@dataclass(frozen=True)
class CollisionSettings:
    """How collisions are handled.

    Attributes:
        body: Cloth-body collision on.
        cloth: Cloth-cloth collision on (section 6.3).
        passes: Alternations of cloth-cloth and cloth-body response per step. The paper keeps
            each action on a stack and answers it with the reaction once the innermost layer
            meets the body (figure 10); in parallel, each pass carries actions one layer
            further in and reactions one layer further out, so ``passes`` at least the number
            of stacked layers plus one resolves a stack. The last response of a step is always
            against the body, so no node ends a step inside it.
        search_margin: Extra reach of the search for the body's triangles [m]. The triangles
            found are remembered and the search is repeated only once some node has moved half
            this far, so a larger margin means fewer searches but more candidates.
        cloth_search_margin: The same for the cloth's own triangles [m] (a search is repeated
            once some node has moved half this far beyond the motion common to all nodes, or
            some node's step half this far from the step it was searched for); None: as
            ``search_margin``, or a quarter of the net's element where that would list the
            set-up positions' own layer (:meth:`CollisionPipeline.default_cloth_margin`).
            Where no node's candidates overflow (:data:`MAX_CANDIDATES`), it changes how often
            the cloth is searched, not the steps (tested): the contacts are only those a search
            with no margin lists too, in an order of their own
            (:func:`~party.collision.cloth.detect_cloth`).
        max_cells: Largest number of intervals per axis in the interval lists.
        crossing_guard: Check steps' ends for edges newly through triangles and revert them
            (:mod:`party.collision.crossing_guard`).
        guard_every: The guard checks every this many steps.
        guard: How the guard searches (:class:`~party.collision.crossing_guard.GuardSettings`).
        body_vertices: Cloth triangles respond to the body's vertices as well (ours:
            :mod:`party.collision.body_vertices`), so that no body vertex comes through a
            triangle between the cloth's nodes (only the vertices the cloth could come near are
            tested: :func:`~party.collision.body_vertices.vertices_to_test`); on with the
            implicit solver (:func:`party.collision.presets.large_step`).
        arrive: A node whose step reaches a body's thickness shell from outside is moved onto
            the shell first and takes its response there (ours:
            :func:`party.collision.body.collide_body`); as printed, it stays where it started.
            On with the implicit solver, whose steps left nodes stopped millimetres off the body.
        landing: Cut a large step into substeps where cloth lands on a body fast
            (:meth:`CollisionPipeline.landing_substeps`; the implicit solver's).
        skip_settled: Passes after a Collision()'s first leave out what the last pass left as
            it was (the same result, bit for bit); False runs every pass over everything.
        exclude_ring: Cloth triangles a node does not collide with: 0, those holding the node
            (the node may not fold through its neighbours' triangles, which keeps sharp folds
            of a coarse net from crossing themselves); 1, also those holding one of its mesh
            neighbours. Either way, also those holding a node nearer along the net than cloth
            of its thickness can fold (``Model.node_near``).
    """

    body: bool = True
    cloth: bool = True
    passes: int = 3
    search_margin: float = 4.0e-3
    cloth_search_margin: float | None = None
    max_cells: int = 256
    exclude_ring: int = 0
    broad_phase: str = "intervals"
    crossing_guard: bool = False
    guard_every: int = 1
    guard: GuardSettings = GuardSettings()
    body_vertices: bool = False
    arrive: bool = False
    landing: bool = True
    skip_settled: bool = True

    def __post_init__(self) -> None:
        if self.broad_phase not in ("intervals", "bvh"):
            raise InvalidInput(f"unknown broad phase {self.broad_phase!r}; known: intervals, bvh")
        for name in ("search_margin", "cloth_search_margin"):
            value = getattr(self, name)
            if value is not None and not value >= 0.0:
                raise InvalidInput(f"{name} must be at least 0 m, got {value!r}")


@wp.kernel
def close_pass(touched: wp.array(dtype=int), skip: int, settled: wp.array(dtype=int), changed: wp.array(dtype=int)):
    """After a pass of Collision(): the nodes it left as they were (``touched`` 0) are
    ``settled`` for the next (where ``skip``); count those it changed (flag 1; a node with only
    :data:`~party.collision.geometry.PUSH_SPENT` is neither) and clear ``touched``."""
    i = wp.tid()
    settled[i] = 0
    if touched[i] == 0 and skip != 0:
        settled[i] = 1
    if (touched[i] & 1) != 0:
        wp.atomic_add(changed, 0, 1)
    touched[i] = 0


@wp.kernel
def carry_settled(touched: wp.array(dtype=int), changed: wp.array(dtype=int), searched_again: wp.array(dtype=int),
                  cloth_contacts: wp.array(dtype=int), settled: wp.array(dtype=int)):
    """A node the last Collision()'s last pass left as it was (not ``touched``: once a pass has
    changed nothing, none is) is settled for this one's first pass, unless ``changed`` since
    (non-zero), ``searched_again`` against the body (its candidates differ) or in cloth contact
    now (detected anew, the contacts may differ from those that pass saw)."""
    i = wp.tid()
    settled[i] = 0
    if touched[i] == 0 and changed[i] == 0 and searched_again[i] == 0 and cloth_contacts[i] == 0:
        settled[i] = 1


class CollisionPipeline:
    """Filters a step's velocities (and start positions) so that no node enters a body or
    crosses a cloth layer: ``v(t+dt) = Collision(v*)`` of eq. (5)."""

    def __init__(self, model: Model, settings: CollisionSettings = CollisionSettings()) -> None:
        self.model = model
        self.settings = settings
        dev = model.device
        n = model.node_count
        self.has_body = settings.body and len(model.collider_faces) > 0
        self.has_cloth = settings.cloth and model.triangle_count > 0
        self.body_moving = bool(np.any(model.collider_velocity != 0.0))
        self.body_margin = float(settings.search_margin)
        self.cloth_margin = float(settings.search_margin if settings.cloth_search_margin is None
                                  else settings.cloth_search_margin)
        self.bvh = settings.broad_phase == "bvh"
        self._touched = wp.zeros(n, dtype=int, device=dev)
        self._settled = wp.zeros(n, dtype=int, device=dev)
        self._changed = wp.zeros(1, dtype=int, device=dev)
        self.searches = 0
        self._flags = wp.zeros(2, dtype=int, device=dev)
        self._cloth_searched = False
        self._overflow = wp.zeros(1, dtype=int, device=dev)
        self._x_ref = wp.zeros(n, dtype=wp.vec3, device=dev)
        self._step_ref = wp.zeros(n, dtype=wp.vec3, device=dev)
        self._motion = wp.zeros(2, dtype=wp.vec3, device=dev)
        self._velocity_sum_ref = wp.zeros(1, dtype=wp.vec3, device=dev)
        self._proposed = wp.zeros(n, dtype=wp.vec3, device=dev)  # v at the step's first Collision()
        self._searched_v = wp.zeros(n, dtype=wp.vec3, device=dev)
        self._searched_again = wp.zeros(n, dtype=int, device=dev)
        self._most = wp.ones(1, dtype=int, device=dev)
        self._body_speed = wp.zeros(1, dtype=float, device=dev)
        self.after_body_search: Callable[..., None] | None = None
        """Called after each search of the body as ``(pipeline, x, v, state, dt, continuing)``:
        an observer, for checks of what the searches keep."""
        self._thickness = float(model.node_thickness.numpy().max())
        if self.bvh:
            # each node's shortest edge [m], for the landing substeps and the implicit solver's re-solve
            self.node_length = wp.array(shortest_edge(model).astype(np.float32), dtype=float, device=dev)
        if self.has_body:
            colliders = model.host.colliders
            size = max(_triangle_size(c.vertices, c.faces) for c in colliders)
            if self.bvh:
                self.body_tree = TriangleBvh(model.collider_faces)
            else:
                self.body_lists = AxisIntervalLists(model.collider_faces, min_cell=size, max_cells=settings.max_cells)
            self.body_faces = wp.zeros((n, MAX_FACES), dtype=int, device=dev)
            self._body_ref = wp.zeros(n, dtype=wp.vec3, device=dev)
            self._body_step_ref = wp.zeros(n, dtype=wp.vec3, device=dev)
            self.body_face_count = wp.zeros(n, dtype=int, device=dev)
            self.body_contact_face = wp.full(n, -1, dtype=int, device=dev)
            self.body_solve_push = wp.zeros(n, dtype=wp.vec3, device=dev)
            self._body_built = False
        tested = (vertices_to_test(model) if self.has_body and settings.body_vertices and model.triangle_count > 0
                  else np.zeros(0, dtype=int))
        self.has_body_vertices = len(tested) > 0
        if self.has_body_vertices:
            normals = np.concatenate([c.vertex_normals() for c in model.host.colliders])
            self.body_vertex_normals = wp.array(normals.astype(np.float32), dtype=wp.vec3, device=dev)
            creases = np.concatenate([c.crease_normals() for c in model.host.colliders])
            self.body_crease_normals = wp.array(creases.astype(np.float32), dtype=wp.vec3, ndim=2, device=dev)
            self.tested_vertices = wp.array(tested.astype(np.int32), dtype=int, device=dev)
            self._vertex_lower = wp.zeros(len(tested), dtype=wp.vec3, device=dev)
            self._vertex_upper = wp.zeros(len(tested), dtype=wp.vec3, device=dev)
            self._vertex_tree: wp.Bvh | None = None
            t = model.triangle_count
            self.body_vertices = wp.zeros((t, MAX_VERTICES), dtype=int, device=dev)
            self.body_vertex_count = wp.zeros(t, dtype=int, device=dev)
            self._vertex_distance = wp.zeros((t, MAX_VERTICES), dtype=float, device=dev)
            self._triangle_ref = wp.zeros((t, 3), dtype=wp.vec3, device=dev)
            self._triangle_step_ref = wp.zeros((t, 3), dtype=wp.vec3, device=dev)
        if self.has_cloth:
            size = _triangle_size(model.host.points, model.triangles)
            if self.bvh:
                self.cloth_tree = TriangleBvh(model.triangle_nodes)
            else:
                self.cloth_lists = AxisIntervalLists(model.triangle_nodes, min_cell=size, max_cells=settings.max_cells)
            self._excluded_offsets, self._excluded = self._excluded_nodes()
            self.cloth_candidates = wp.zeros((n, MAX_CANDIDATES), dtype=int, device=dev)
            self.cloth_candidate_count = wp.zeros(n, dtype=int, device=dev)
            self._candidate_distance = wp.zeros((n, MAX_CANDIDATES), dtype=float, device=dev)
            self.contact_tri = wp.zeros((n, MAX_CONTACTS), dtype=int, device=dev)
            self.contact_w = wp.zeros((n, MAX_CONTACTS), dtype=wp.vec3, device=dev)
            self.contact_n = wp.zeros((n, MAX_CONTACTS), dtype=wp.vec3, device=dev)
            self.contact_d = wp.zeros((n, MAX_CONTACTS), dtype=float, device=dev)
            self.contact_count = wp.zeros(n, dtype=int, device=dev)
            if settings.cloth_search_margin is None:
                self.cloth_margin = self.default_cloth_margin()
        if self.has_cloth or self.has_body_vertices:
            # per-node sums of the responses of one pass, applied and reset after each
            self.dv = wp.zeros(n, dtype=wp.vec3, device=dev)
            self.dx = wp.zeros(n, dtype=wp.vec3, device=dev)
            self.hits = wp.zeros(n, dtype=int, device=dev)

    def default_cloth_margin(self) -> float:
        """The cloth search's margin [m] when none is set: ``search_margin`` unless under it
        the model's set-up positions list more than :data:`OWN_LAYER_LISTED` cloth triangles a
        node beyond those they list with none; then :data:`CLOTH_MARGIN_PER_ELEMENT` of the
        net's median element, if that is narrower (two searches at set-up)."""
        x = self.model.node_rest_points
        widest = float(self.settings.search_margin)
        own_layer = self.listed_per_node(x, widest) > self.listed_per_node(x, 0.0) + OWN_LAYER_LISTED
        self._overflow.zero_()  # the run's own searches report theirs
        if not own_layer:
            return widest
        element = float(np.median(self.model.host.element_rest_length))
        return min(widest, CLOTH_MARGIN_PER_ELEMENT * element)

    def listed_per_node(self, x: wp.array, margin: float) -> float:
        """Cloth triangles a node, on average, that a search of nodes at rest at ``x`` with
        ``margin`` [m] lists (a host sync). The next Collision() searches afresh, and
        :attr:`searches` does not count this one."""
        kept = self.cloth_margin
        self.cloth_margin = margin
        self._search_cloth(x, wp.zeros_like(x), 0.0, False)
        self.cloth_margin = kept
        self.searches -= 1
        self._cloth_searched = False
        return float(self.cloth_candidate_count.numpy().mean())

    @property
    def carried(self) -> tuple[str, ...]:
        """What a step reads of the last (:mod:`party.solvers.memory`): the face each node was
        last in contact with and the push the body gave it, and the body candidates, from which
        the implicit solver's body planes start a step."""
        return ("body_contact_face", "body_solve_push", "body_faces", "body_face_count") if self.has_body else ()

    def forget_search(self) -> None:
        """Drop the search structures and search the body and the cloth afresh at the next
        Collision() (:func:`party.solvers.memory.forget`: a BVH's shape depends on the boxes it
        was first built from)."""
        self._cloth_searched = False
        if self.has_body:
            self._body_built = False
            if self.bvh:
                self.body_tree.forget()
        if self.has_body_vertices:
            self._vertex_tree = None
        if self.has_cloth and self.bvh:
            self.cloth_tree.forget()

    def apply(self, x: wp.array, v: wp.array, state: State, dt: float, *, continuing: bool = False,
              changed: wp.array | None = None) -> None:
        """Collision(): modify velocities ``v`` (and start positions ``x``) in place.

        Repeats the search of the body's triangles and vertices for each node and cloth triangle
        that may have left the region searched for it last time, and that of the cloth's
        triangles, for every node, once some node may have moved so, beyond the motion common to
        all nodes (:func:`~party.collision.cloth.moved_beyond`; this reads two flags from the
        device). ``continuing`` marks a second Collision() within one step (after the plastic
        limit): the body's candidates also serve a node whose step stays within half the margin
        of the box of the step they were searched for (:func:`~party.collision.body.covered`),
        and only where the limit moved it beyond both is it searched again (reused without this
        check, the candidates would miss a node that the limit sent beyond them). The cloth's
        serve, at either Collision(), while every node stays within half the margin of where it
        was searched from, or every node's step within half the margin of the step it was
        searched for (a search in the second looks along the step the first had where the
        node's present step lies near it: :func:`~party.collision.cloth.searched_velocity`).

        Each pass after the first leaves out what the last pass left as it was: a cloth triangle
        against the body's vertices whose nodes it did not change, a cloth contact none of whose
        nodes it or this pass has changed (or sent a correction) so far, a node's body response
        where neither has. On the same positions and velocities they would compute what they
        computed in the last pass, which changed nothing, so the result is bit for bit that of
        full passes; once a pass changes nothing, the passes stop. After the first pass only a
        few layers' worth of nodes still change, so the later passes cost little.

        ``changed`` (with ``continuing``) continues the last Collision() of this step: its first
        pass leaves out, likewise, what that one's last pass left as it was, unless non-zero in
        ``changed`` (nodes whose velocity was changed since, by the plastic limit), searched
        again against the body, or in cloth contact (the contacts are detected anew)."""
        m = self.model
        dev = m.device
        if continuing:
            self._searched_again.zero_()
        if self.has_body:
            self._search_body(x, v, state, dt, continuing)
        if self.has_cloth:
            if not continuing:
                wp.copy(self._proposed, v)
            self._motion.zero_()
            self._flags.zero_()
            launch(sum_motion, dim=m.node_count, inputs=[x, v, self._x_ref, self._motion], device=dev)
            launch(moved_beyond, dim=m.node_count,
                   inputs=[x, v, self._x_ref, self._step_ref, self._motion, self._velocity_sum_ref,
                           1.0 / m.node_count, dt, self.cloth_margin, self._flags], device=dev)
            left = self._flags.numpy()
            if not self._cloth_searched or (left[0] and left[1]):
                self._search_cloth(x, v, dt, continuing)
        if self.has_cloth:
            launch_items(detect_cloth, 0, m.node_count,
                         [x, v, m.node_thickness, m.triangle_nodes, self.cloth_candidates, self.cloth_candidate_count,
                          dt, self.contact_tri, self.contact_w, self.contact_n, self.contact_d, self.contact_count], dev)
        if changed is not None and continuing:
            contacts = self.contact_count if self.has_cloth else changed
            launch(carry_settled, dim=m.node_count,
                   inputs=[self._touched, changed, self._searched_again, contacts, self._settled], device=dev)
        else:
            self._settled.zero_()
        self._touched.zero_()
        passes = max(self.settings.passes, 1) if self.has_cloth else 1
        for k in range(passes):
            self.vertex_pass(x, v, state, dt)
            if self.has_cloth:
                launch(respond_cloth, dim=m.node_count,
                       inputs=[x, v, m.node_inv_mass, m.node_thickness, m.node_gamma, m.node_kappa,
                               m.triangle_nodes, self.contact_tri, self.contact_w, self.contact_n,
                               self.contact_count, dt, self._settled, self._touched, self.dv, self.dx, self.hits],
                       device=dev)
                launch(apply_cloth_response, dim=m.node_count,
                       inputs=[x, v, self.dv, self.dx, self.hits, self._touched], device=dev)
            self.body_pass(x, v, state, dt)
            if k + 1 < passes:
                self._changed.zero_()
                launch(close_pass, dim=m.node_count,
                       inputs=[self._touched, int(self.settings.skip_settled), self._settled, self._changed], device=dev)
                if int(self._changed.numpy()[0]) == 0:
                    break

    def landing_substeps(self, state: State, dt: float) -> int:
        """Substeps a step of ``dt`` [s] from ``state`` needs so that no node near a body moves
        farther than :data:`~party.collision.landing.LANDING_REACH` of its shortest edge
        relative to it in one substep, its velocity taken at both ends of the step under
        gravity (:mod:`party.collision.landing`; reads one number from the device). 1 with the
        interval lists' broad phase, which only the explicit solver's short steps use. Raises
        :class:`~party.errors.SimulationUnstable` where more than
        :data:`~party.collision.landing.MAX_LANDING_SUBSTEPS` would be needed."""
        if not self.settings.landing or not self.has_body or not self.bvh:
            return 1
        m = self.model
        self._body_speed.zero_()
        if self.body_tree.bvh is None or self.body_moving:
            self.body_tree.build(state.collider_q, state.collider_qd, dt, 0.0)
            launch(largest_speed, dim=len(state.collider_qd), inputs=[state.collider_qd, self._body_speed],
                   device=m.device)
        self._most.fill_(1)
        launch(landing_substeps, dim=m.node_count,
               inputs=[state.node_q, state.node_qd, m.node_inv_mass, m.node_thickness, self.node_length,
                       self.body_tree.id, m.collider_faces, state.collider_qd, self._body_speed, m.gravity, dt,
                       self.body_margin, LANDING_REACH, self._most], device=m.device)
        needed = int(self._most.numpy()[0])
        if needed > MAX_LANDING_SUBSTEPS:
            raise SimulationUnstable(f"a step of {dt:g} s is too long for cloth meeting the body: landing would take "
                                     f"{needed} substeps (at most {MAX_LANDING_SUBSTEPS}); use a step of at most "
                                     f"{dt * MAX_LANDING_SUBSTEPS / needed:.2g} s (--dt)")
        return needed

    def vertex_pass(self, x: wp.array, v: wp.array, state: State, dt: float) -> None:
        """Cloth triangles against the body's vertices (:mod:`party.collision.body_vertices`)
        over the candidates of the last search, at the start of every pass, so that the pass's
        cloth responses carry a push on to the layers above and its body pass has the last word
        for every node: run once before the passes, a push from the body's vertices would stop at
        the first layer and the cloth above would settle onto it over many steps."""
        if not self.has_body_vertices:
            return
        m = self.model
        launch(respond_body_vertices, dim=m.triangle_count,
               inputs=[x, v, m.node_inv_mass, m.node_thickness, m.triangle_nodes, state.collider_q,
                       state.collider_qd, self.body_vertex_normals, self.body_crease_normals, self.body_vertices,
                       self.body_vertex_count, dt, self._settled, self.body_contact_face, m.collider_faces,
                       self.dv, self.dx, self.hits], device=m.device)
        launch(apply_cloth_response, dim=m.node_count,
               inputs=[x, v, self.dv, self.dx, self.hits, self._touched], device=m.device)

    def body_pass(self, x: wp.array, v: wp.array, state: State, dt: float) -> None:
        """One cloth-body response pass (eqs. 8-12) over the candidates of the last search."""
        if not self.has_body:
            return
        m = self.model
        launch_items(collide_body, 0, m.node_count,
                     [x, v, m.node_inv_mass, m.node_thickness, m.node_friction, m.node_restitution, state.collider_q,
                      state.collider_qd, m.collider_normals, m.collider_faces, self.body_faces, self.body_face_count, dt,
                      int(self.settings.arrive), self._settled, self._touched, self.body_contact_face,
                      self.body_solve_push], m.device)

    def _search_body(self, x: wp.array, v: wp.array, state: State, dt: float, continuing: bool) -> None:
        """Search the body's triangles (and vertices) again for the nodes (cloth triangles) that
        may have left the region searched for them: each stays within margin/2 of where it
        was searched from, and its box grew by eps + margin/2; static body triangles do not
        move at all. A moving body is searched again for every node, every step, but not in
        a ``continuing`` Collision() of the same step (:func:`~party.collision.body.covered`).
        Searching node by node matters at rest, where a few swinging nodes would otherwise have
        every node searched at almost every step."""
        m = self.model
        dev = m.device
        half = 0.5 * self.body_margin
        everything = int((self.body_moving or not self._body_built) and not continuing)
        if everything:
            self.searches += 1
            if self.bvh:
                self.body_tree.build(state.collider_q, state.collider_qd, dt, 0.0)
            else:
                self.body_lists.build_checked(state.collider_q, state.collider_qd, dt, 0.0)
            self._body_built = True
        gather, structure = ((gather_body_faces_bvh, self.body_tree.id) if self.bvh
                             else (gather_body_faces, self.body_lists.lists))
        launch_items(gather, 0, m.node_count,
                     [x, v, m.node_inv_mass, m.node_thickness, structure, dt, half, everything, int(continuing),
                      self._body_ref, self._body_step_ref, self._searched_again, m.node_ignored_parts,
                      m.collider_face_parts, self.body_faces, self.body_face_count, self._overflow], dev)
        if self.has_body_vertices:
            if self._vertex_tree is None or (self.body_moving and not continuing):
                launch(vertex_boxes, dim=self.tested_vertices.shape[0],
                       inputs=[self.tested_vertices, state.collider_q, state.collider_qd, dt, half,
                               self._vertex_lower, self._vertex_upper], device=dev)
                if self._vertex_tree is None:
                    self._vertex_tree = wp.Bvh(self._vertex_lower, self._vertex_upper)
                else:
                    self._vertex_tree.refit()
            launch_items(gather_body_vertices, 0, m.triangle_count,
                         [x, v, m.node_thickness, m.triangle_nodes, self._vertex_tree.id, self.tested_vertices,
                          state.collider_q, state.collider_qd, dt, half, everything, int(continuing),
                          self._triangle_ref, self._triangle_step_ref, self._searched_again,
                          m.node_ignored_parts, m.collider_vertex_parts, self.body_vertices,
                          self.body_vertex_count, self._vertex_distance, self._overflow], dev)
        if self.after_body_search is not None:
            self.after_body_search(self, x, v, state, dt, continuing)

    def _search_cloth(self, x: wp.array, v: wp.array, dt: float, continuing: bool) -> None:
        """Search the cloth's triangles again for every node: a node stays within margin/2 of
        where it was searched from, beyond the nodes' common motion (else a new search), and so
        does every cloth triangle's node:
        node boxes grow by eps + margin/2 and cloth triangle boxes by margin/2. In a
        ``continuing`` Collision() each node's step is searched for as
        :func:`~party.collision.cloth.searched_velocity` gives it."""
        m = self.model
        dev = m.device
        self.searches += 1
        half = 0.5 * self.cloth_margin
        if continuing:
            launch(searched_velocity, dim=m.node_count, inputs=[x, v, self._proposed, dt, half, self._searched_v],
                   device=dev)
            v = self._searched_v
        if self.bvh:
            self.cloth_tree.build(x, v, dt, half)
            gather, structure = gather_cloth_triangles_bvh, self.cloth_tree.id
        else:
            self.cloth_lists.build_checked(x, v, dt, half)
            gather, structure = gather_cloth_triangles, self.cloth_lists.lists
        launch_items(gather, 0, m.node_count,
                     [x, v, m.node_thickness, m.triangle_nodes, self._excluded_offsets, self._excluded, structure,
                      dt, half, self.cloth_candidates, self.cloth_candidate_count, self._candidate_distance,
                      self._step_ref, self._overflow], dev)
        wp.copy(self._x_ref, x)
        wp.copy(self._velocity_sum_ref, self._motion, src_offset=1, count=1)
        self._cloth_searched = True

    def _excluded_nodes(self) -> tuple[wp.array, wp.array]:
        """CSR (offsets, node ids) of the nodes whose triangles each node does not collide
        with, the node itself aside: those nearer along the net than cloth of its thickness
        can fold (``Model.node_near``) and, with ``exclude_ring`` 1, its mesh neighbours."""
        m = self.model
        if self.settings.exclude_ring == 0:
            return m.node_near_offsets, m.node_near
        rows, ids = [], []
        for offsets, nodes in ((m.node_near_offsets, m.node_near), (m.node_neighbor_offsets, m.node_neighbors)):
            rows.append(np.repeat(np.arange(m.node_count), np.diff(offsets.numpy())))
            ids.append(nodes.numpy())
        pairs = np.unique(np.c_[np.concatenate(rows), np.concatenate(ids)], axis=0)
        offsets, order = csr_order(pairs[:, 0], m.node_count)
        return (wp.array(offsets.astype(np.int32), dtype=int, device=m.device),
                wp.array(pairs[order, 1].astype(np.int32), dtype=int, device=m.device))

    def candidate_overflow(self) -> int:
        """How many candidates (body or cloth triangles of a node, body vertices of a cloth
        triangle) were dropped for want of room (host sync; a lower bound when the gathering
        ran on several CPU threads, non-zero iff any was)."""
        return int(self._overflow.numpy()[0])


def _triangle_size(points: np.ndarray, faces: np.ndarray) -> float:
    """Largest axis-aligned extent of any triangle [m]."""
    if len(faces) == 0:
        return 1.0e-3
    p = points[faces]
    return float(max((p.max(axis=1) - p.min(axis=1)).max(), 1.0e-4))
