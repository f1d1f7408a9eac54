"""A large-step solver on the same Model and State: implicit Euler by Vertex Block Descent."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np
import warp as wp

from ...collision import CollisionSettings
from ...collision.presets import large_step
from ...errors import InvalidInput
from ...launch import launch, launch_items, launch_workers, worker_count, worker_sync
from ...model import Control, Model, State
from ...model.csr import csr_order
from ..aero import Air, AirForces
from ..explicit.kernels import kinetic_damping
from ..hysteresis import slip_in_world
from ..filters import StepFilters
from ..plastic_limit import OVER_RELAXATION
from .descent import DESCENT, DescentTerms
from .kernels import (body_planes, chebyshev_blend, contact_changes, contact_region, contact_resolve_start,
                      contact_resolved_velocity, inertial_target, onto_planes, record_correction, spread_region,
                      step_velocity)


SLIDER_STEP_RATIO = 600.0
"""Largest stuck bending stiffness over inertia, L_ii dt^2 / m_i with L the bending matrix with
its sliders stuck (:func:`slider_stiffness`), at the nodes of a bending-hysteresis slider in one
(sub)step. Beyond it the sweeps leave a node's fall unresisted in the first steps and the slider
keeps the kink: a cantilever whose root moment stays below HB must bend only as far as its
stuck stiffness allows, as the explicit solver's does, and does so within this ratio."""

STIFFNESS_PER_SWEEP = 400.0
"""Stiffness over inertia, K_ii dt^2 / m_i (the largest over the nodes: springs, membrane and
bending), that one sweep of a (sub)step answers for: a step takes at least K_ii dt^2 / m_i
over this many sweeps. With fewer, the sweeps fall so far short of the solve that their
Chebyshev-accelerated error feeds on itself from step to step, and cloth held up by its
stiffness crumples (a denim Cusick specimen does; at this ratio it drapes as with the explicit
solver). Garments in wool flannel at 15-30 mm stay within a few times this, so their sweeps are
as given; denim's grow below about 20 mm. Substeps in place of sweeps hold such cloth only for a
while: the sweeps' error, not the step, is what lets it crumple."""

MAX_SWEEPS = 100
"""Most sweeps :data:`STIFFNESS_PER_SWEEP` gives a (sub)step; a stiffer model takes substeps."""

CONTACT_ROUNDS = 3
"""Most times a (sub)step solves again around the nodes Collision() stopped
(:meth:`SolverImplicit.resolve_contacts`; the default of ``contact_rounds``). Each round lets
the cloth follow the nodes the last one stopped; after three, the few elements a dress's frames
still hold beyond its limit are no more than a fraction of those one round leaves."""

CONTACT_SWEEPS = 5
"""Sweeps of each re-solve: the region is small and starts near its solution, and more sweeps
leave no less stretch."""

CONTACT_REACH = 0.01
"""A node off the body whose end of step Collision() moved farther than this share of its
shortest edge starts a re-solve around it."""

CONTACT_RINGS = 6
"""Rings of neighbours (through elements and bending rows, so two rings of the net each)
around such a node that are re-solved; three left the dress's frames with more stretch."""


class SolverImplicit:
    """Implicit (backward) Euler on the paper's net plus shear diagonals, bending hinges and
    the optional continuum membrane, solved by Vertex Block Descent (VBD, Chen et al. 2024):
    each iteration visits the nodes colour by colour and moves each to the minimum of its local
    incremental potential (one 3x3 Newton step, in the step's displacement, which single
    precision resolves where a position would lose it). Steps of 1/60 s in a few substeps stay
    stable for every library fabric (tested), at the cost of the stiffest modes being damped
    and, for stiff fabrics at few sweeps, an approximate solve (see docs/design.md).

    The step ends as the explicit one does (:class:`party.solvers.filters.StepFilters`): the
    velocity the solve proposes, v* = (x - x(t)) / dt, goes through the plastic limit and the
    paper's Collision() (continuous node-along-step detection against bodies and cloth, the
    friction cone, restitution and the body's velocity, eqs. 8-14), then eq. (4). Contact is
    therefore the same as the explicit solver's at any step size; its candidates are found with
    a BVH over the interval lists' boxes (``broad_phase="bvh"``), which finds the same
    triangles faster.

    Bending hysteresis's elements are part of the solve (backward Euler's return mapping,
    :mod:`party.solvers.hysteresis`); with them a step is cut into :meth:`substeps` where the
    mesh is fine for the fabric's bending.

    Args:
        model: The model to advance.
        iterations: VBD sweeps per (sub)step, or more where the model is stiff for its
            inertia (:meth:`sweeps`).
        chebyshev: Estimated spectral radius rho of the sweeps for Chebyshev acceleration (0:
            none; fixed once the first step has been recorded).
        collision: Collision settings; ``None`` switches collision off.
        air: Wind and air drag; ``None`` for none.
        plastic_passes: See :class:`~party.solvers.filters.StepFilters`; the sweeps are
            over-relaxed by :data:`~party.solvers.plastic_limit.OVER_RELAXATION`.
        kinetic_damping: ``(max_speed [m/s], keep [-])`` to filter v* for static relaxation
            (:mod:`party.solvers.relax`); None for dynamics.
        contact_rounds: Re-solves of the cloth around the nodes Collision() stopped, per
            (sub)step (:meth:`resolve_contacts`); 0 for none. Runs that seek only a rest shape
            (static relaxation, :func:`~party.solvers.settle.settle`) take none.
    """

    name = "implicit"
    default_dt = 1.0 / 300.0
    """A 60 Hz frame in five steps."""
    settle_seconds = 300.0
    creep = 0.2
    """Its sweeps, cut short in finely meshed stiff cloth, let the last millimetres creep in over
    tens of seconds: a settling asks it for a five times slower creep."""

    carried = ("_correction",)
    """What the next step reads of the last (:mod:`party.solvers.memory`): the correction the
    body gave the solve, which its inertial target starts from."""

    def __init__(self, model: Model, *, iterations: int = 10, chebyshev: float = 0.9,
                 collision: CollisionSettings | None = CollisionSettings(), air: Air | None = None,
                 plastic_passes: int = 32, kinetic_damping: tuple[float, float] | None = None,
                 contact_rounds: int = CONTACT_ROUNDS) -> None:
        if iterations < 1:
            raise InvalidInput(f"implicit solver needs at least 1 iteration, got {iterations}")
        self.model = model
        self.kinetic_damping = kinetic_damping
        self.iterations = int(iterations)
        if collision is not None:
            collision = replace(collision, broad_phase="bvh")
        self.filters = StepFilters(model, collision, plastic_passes, limit_after_contact=True,
                           max_speed=kinetic_damping[0] if kinetic_damping is not None else None,
                           plastic_over_relaxation=OVER_RELAXATION,
                           contact_resolve=self.resolve_contacts if contact_rounds > 0 else None,
                           contact_rounds=contact_rounds)
        self.collision = self.filters.collision
        self.air = AirForces(model, air) if air is not None else None
        dev = model.device
        n = model.node_count
        self._f_ext = wp.zeros(n, dtype=wp.vec3, device=dev)
        self._y = wp.zeros(n, dtype=wp.vec3, device=dev)
        self._d = wp.zeros(n, dtype=wp.vec3, device=dev)
        self._d_previous = wp.zeros(n, dtype=wp.vec3, device=dev)
        self._d_before = wp.zeros(n, dtype=wp.vec3, device=dev)
        self._correction = wp.zeros(n, dtype=wp.vec3, device=dev)
        self._plane_normal = wp.zeros(n, dtype=wp.vec3, device=dev)
        self._plane_offset = wp.zeros(n, dtype=float, device=dev)
        self._planes = self.collision is not None and self.collision.has_body
        self.chebyshev = float(chebyshev)
        bend = model.bending_matrix(friction=False)
        rows = node_neighbours(model, bend)
        self._neighbour_offsets = wp.array(rows.offsets, dtype=int, device=dev)
        self._neighbour_nodes = wp.array(rows.nodes, dtype=int, device=dev)
        self._neighbour_params = wp.array(rows.params.astype(np.float32), dtype=wp.vec4, device=dev)
        self._bend_diagonal = wp.array(rows.bend_diagonal.astype(np.float32), dtype=float, device=dev)
        self._slider_stiffness = slider_stiffness(model)
        self._coupling = NodeCoupling.of(model, bend)
        self._node_stiffness = self._coupling.largest_rate()
        self._scratch: State | None = None
        slider_offsets, slider_slots = node_sliders(model)
        self._slider_offsets = wp.array(slider_offsets, dtype=int, device=dev)
        self._slider_slots = wp.array(slider_slots, dtype=int, device=dev)
        self._slip_world = wp.zeros(model.hinge_count, dtype=wp.vec3, device=dev)
        self._sliding = len(slider_slots) > 0
        tri_offsets, tri_slots = node_triangles(model)
        self._tri_offsets = wp.array(tri_offsets, dtype=int, device=dev)
        self._tri_slots = wp.array(tri_slots, dtype=int, device=dev)
        color_offsets, colored = color_nodes(model)
        self.color_offsets = color_offsets
        self._colored = wp.array(colored, dtype=int, device=dev)
        self._color_offsets = wp.array(color_offsets, dtype=int, device=dev)
        self._omegas_by_dt: dict[float, tuple[np.ndarray, wp.array]] = {}
        self._sync = worker_sync(dev)
        self.workers = worker_count(len(colored), dev)
        self._terms = self._descent_terms()
        self._contact_inv_mass = wp.zeros(n, dtype=float, device=dev)
        self._contact_terms = self._descent_terms()
        self._contact_terms.inv_mass = self._contact_inv_mass
        self._held = wp.zeros(n, dtype=int, device=dev)
        self.serial_region = wp.get_device(dev).is_cpu
        self._source = wp.zeros(n, dtype=int, device=dev)
        self._depth = wp.zeros(n, dtype=int, device=dev)
        self._queue = wp.zeros(n, dtype=int, device=dev)
        self._resolved = wp.zeros(n, dtype=int, device=dev)
        self._sources = wp.zeros(1, dtype=int, device=dev)
        self._body_face = (self.collision.body_contact_face if self._planes
                           else wp.full(n, -1, dtype=int, device=dev))
        self._no_omegas = wp.zeros(0, dtype=float, device=dev)
        self._contact_offsets = wp.zeros(len(color_offsets), dtype=int, device=dev)
        self._contact_nodes = wp.zeros(len(colored), dtype=int, device=dev)
        self._descent = DESCENT[len(tri_slots) > 0 or self._sliding]
        self._graphs: dict = {}
        self._capture = True

    @classmethod
    def configured(cls, model: Model, *, collision: CollisionSettings | None = CollisionSettings(),
                   air: Air | None = None, static: bool = False, kinetic_damping: tuple[float, float] | None = None,
                   iterations: int | None = None, contact_rounds: int | None = None) -> "SolverImplicit":
        """The implicit solver with :func:`~party.collision.presets.large_step` collision; runs
        that seek only a rest shape (``static``: relaxations, settling) take no contact re-solves
        (:meth:`resolve_contacts`): they are judged by the rest shape, whose stretch the plastic
        limit takes up over the steps after."""
        rounds = 0 if static else (CONTACT_ROUNDS if contact_rounds is None else contact_rounds)
        return cls(model, collision=large_step(collision), air=air, kinetic_damping=kinetic_damping,
                   contact_rounds=rounds, **({} if iterations is None else {"iterations": iterations}))

    @classmethod
    def relaxation_step(cls, model: Model) -> float:
        """Its default step: large steps are what it is for."""
        return cls.default_dt

    @classmethod
    def dynamics_step(cls, model: Model, resolve_period: float | None = None) -> float:
        """Its default step, or 1/200 of ``resolve_period`` [s] where a motion of that period
        must be resolved (backward Euler's period error is then (2 pi / 200)^2 / 3, about 0.03 %)."""
        return cls.default_dt if resolve_period is None else min(cls.default_dt, resolve_period / 200.0)

    def stable_time_step(self) -> float:
        """Any step: backward Euler is unconditionally stable (stiff cloth takes more sweeps
        and substeps instead, :meth:`sweeps`, :meth:`substeps`)."""
        return math.inf

    def flush(self, state: State) -> None:
        """Run a crossing check that the guard's interval has left pending."""
        self.filters.flush(state)

    def step(self, state_in: State, state_out: State, control: Control, dt: float) -> None:
        """Advance ``state_in`` by ``dt`` [s] into ``state_out`` (distinct objects; swap after),
        in :meth:`substeps` equal substeps, or more where cloth lands on a body
        (:meth:`~party.collision.CollisionPipeline.landing_substeps`)."""
        if not dt > 0.0:
            raise InvalidInput(f"time step must be positive, got {dt}")
        count = self.substeps(dt)
        if self.collision is not None:
            count = max(count, self.collision.landing_substeps(state_in, dt))
        if count == 1:
            self._advance(state_in, state_out, control, dt)
            return
        if self._scratch is None:
            self._scratch = self.model.state()
        source = state_in
        for k in range(count):
            target = state_out if (count - 1 - k) % 2 == 0 else self._scratch
            self._advance(source, target, control, dt / count)
            source = target

    def node_steps(self, x_start: np.ndarray, disp: np.ndarray, y: np.ndarray, dt: float,
                   slip_world: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Each node's gradient [N] and Hessian block [N/m] of the incremental potential the
        sweeps minimise, G(d) = sum_i m_i / (2 dt^2) |d_i - y_i|^2 + E(x(t) + d) plus the
        dampers' c / (2 dt) |d_k - d_i|^2, at displacements ``disp`` [m] from ``x_start`` [m]
        with inertial targets ``y`` (displacements [m]) and the hysteresis sliders' slips
        ``slip_world`` (curvature vectors [1/m], one per stencil; default none), as a sweep's
        Newton step takes them. Shapes (n, 3) and (n, 3, 3). For checks of the energies against
        finite differences; a step sets ``y`` and the slips itself."""
        dev = self.model.device
        n = self.model.node_count
        start = wp.array(np.asarray(x_start, np.float32), dtype=wp.vec3, device=dev)
        d = wp.array(np.asarray(disp, np.float32), dtype=wp.vec3, device=dev)
        self._y.assign(np.asarray(y, np.float32))
        self._slip_world.assign(np.zeros((self.model.hinge_count, 3), np.float32) if slip_world is None
                                else np.asarray(slip_world, np.float32))
        grad = wp.zeros(n, dtype=wp.vec3, device=dev)
        hess = wp.zeros(n, dtype=wp.mat33, device=dev)
        wp.launch(self._descent.node_steps, dim=n, inputs=[self._terms, start, float(dt), d, grad, hess], device=dev)
        return grad.numpy().astype(float), hess.numpy().astype(float)

    def descend_once(self, x_start: np.ndarray, disp: np.ndarray, y: np.ndarray, dt: float,
                     plane_normal: np.ndarray | None = None, plane_offset: np.ndarray | None = None) -> np.ndarray:
        """One Newton step of every free node on its share of the incremental potential (as
        :meth:`node_steps` takes it), in node order, each node's neighbours as the steps before
        left them, with body planes ``plane_normal`` (unit, (n, 3); zero: none) and
        ``plane_offset`` [m] ((n,)) that a node must stay on the outer side of. Returns the
        displacements [m] after. For checks of a sweep against its quadratic model; a step
        sets its planes from the last Collision() itself."""
        dev = self.model.device
        n = self.model.node_count
        start = wp.array(np.asarray(x_start, np.float32), dtype=wp.vec3, device=dev)
        d = wp.array(np.asarray(disp, np.float32), dtype=wp.vec3, device=dev)
        self._y.assign(np.asarray(y, np.float32))
        self._plane_normal.assign(np.zeros((n, 3), np.float32) if plane_normal is None
                                  else np.asarray(plane_normal, np.float32))
        self._plane_offset.assign(np.zeros(n, np.float32) if plane_offset is None
                                  else np.asarray(plane_offset, np.float32))
        order = wp.array(np.arange(n, dtype=np.int32), dtype=int, device=dev)
        wp.launch(self._descent.block_descent, dim=n, inputs=[0, order, self._terms, start, float(dt), d], device=dev)
        self._plane_normal.zero_()
        return d.numpy().astype(float)

    def worker_yields(self) -> int:
        """How often a sweep worker thread, waiting for the others, has given its core away
        (after :class:`~party.launch.LaunchSettings`' ``yield_after_spins``; a running count, read
        from the device): how much a busy machine is slowing the sweeps."""
        return int(self._sync.counters.numpy()[3])

    def substeps(self, dt: float) -> int:
        """Substeps a step of ``dt`` [s] takes: as many as keep each substep's stiffness within
        :data:`MAX_SWEEPS` sweeps (:meth:`sweeps`) and, with bending hysteresis, its stuck
        bending stiffness within :data:`SLIDER_STEP_RATIO` times its inertia."""
        limits = ((self._slider_stiffness, SLIDER_STEP_RATIO),
                  (self._node_stiffness, STIFFNESS_PER_SWEEP * MAX_SWEEPS))
        return max(1, *(math.ceil(math.sqrt(rate * dt * dt / ratio) - 1e-9) for rate, ratio in limits))

    def sweeps(self, dt: float) -> int:
        """Sweeps a (sub)step of ``dt`` [s] takes: ``iterations``, or more where the model is
        stiff for its inertia (:data:`STIFFNESS_PER_SWEEP`), up to :data:`MAX_SWEEPS`."""
        needed = math.ceil(self._node_stiffness * dt * dt / STIFFNESS_PER_SWEEP - 1e-9)
        return max(self.iterations, min(MAX_SWEEPS, needed))

    def spectral_radius(self, dt: float) -> float:
        """The spectral radius rho the Chebyshev acceleration assumes for a (sub)step of ``dt``
        [s]: ``chebyshev``, or less where the nodes are so lightly coupled for their inertia that
        the sweeps converge faster (:meth:`NodeCoupling.jacobi_bound`): assuming a larger radius
        than the sweeps' own over-weights their history and slows them (a finely stepped strip's
        period comes out long)."""
        return min(self.chebyshev, self._coupling.jacobi_bound(dt))

    def _omegas(self, dt: float) -> tuple[np.ndarray, wp.array]:
        """Chebyshev's weights for sweeps of a (sub)step of ``dt`` [s], on the host and the
        device (made once per step size)."""
        if dt not in self._omegas_by_dt:
            values = chebyshev_weights(max(MAX_SWEEPS, self.iterations), self.spectral_radius(dt))
            self._omegas_by_dt[dt] = values, wp.array(values, dtype=float, device=self.model.device)
        return self._omegas_by_dt[dt]

    def _advance(self, state_in: State, state_out: State, control: Control, dt: float) -> None:
        m = self.model
        self._f_ext.zero_()
        if self.air is not None:
            self.air.accumulate(state_in.node_q, state_in.node_qd, control.wind, self._f_ext)
        key = (state_in.node_q.ptr, state_in.node_qd.ptr, state_out.node_q.ptr, state_out.node_qd.ptr,
               control.kinematic_velocity.ptr, float(dt))
        graph = self._graphs.get(key)
        if graph is None and self._capture and self.workers == 1:
            if len(self._graphs) >= 8:  # state pairs: two swapped states, and a scratch one for substeps
                self._graphs.clear()
            try:
                with wp.ScopedCapture(device=m.device) as capture:
                    self._solve(state_in, state_out, control, dt)
                graph = self._graphs[key] = capture.graph
            except Exception:  # devices or settings without graph capture launch kernel by kernel
                self._capture = False
        if graph is not None:
            wp.capture_launch(graph)
        else:
            self._solve(state_in, state_out, control, dt)
        if self.kinetic_damping is not None:
            launch(kinetic_damping, dim=m.node_count,
                   inputs=[state_in.node_qd, state_out.node_qd, *map(float, self.kinetic_damping)], device=m.device)
        self.filters.finish(state_in, state_out, dt)

    def resolve_contacts(self, state_in: State, state_out: State, x_before: wp.array, v_before: wp.array, dt: float,
                         first: bool) -> wp.array | None:
        """Solve the step again for the cloth around the nodes the last Collision() stopped
        (:data:`~party.solvers.filters.ContactResolve`; ours, after the constraint filtering
        of Baraff and Witkin 1998). Collision()'s eqs. (8)-(14) change a node's velocity after
        the solve; over the paper's 0.1 ms the springs spread that change to its neighbours in
        the next steps, but over a large step a node that meets another layer stops within the
        step while its neighbours, solved without that stop, move on, and the last Collision()
        leaves their elements stretched. So every node Collision() changed is held as it left
        it (for the rest of the step), and the free nodes within :data:`CONTACT_RINGS` rings
        of one whose end of step it moved farther than :data:`CONTACT_REACH` of its shortest
        edge take :data:`CONTACT_SWEEPS` sweeps of the same implicit step from where they are,
        so that they follow the held nodes within the step; a dress draped in large steps then
        keeps its elongation near the explicit solver's. Returns the nodes re-solved
        (None where none was moved so far; reads one number from the device). Called only
        where the model has cloth collision (:class:`~party.solvers.filters.StepFilters`). On the
        CPU (``serial_region``) the sweeps visit the re-solved nodes alone, listed by a
        breadth-first search from the moved ones on one thread
        (:func:`~.kernels.contact_region`); on a GPU the region grows ring by ring, a thread per
        node (:func:`~.kernels.spread_region`), and the sweeps run over every node, those out
        of it held (the same result, bit for bit)."""
        m = self.model
        dev = m.device
        if first:
            self._held.zero_()
        self._sources.zero_()
        launch(contact_changes, dim=m.node_count,
               inputs=[x_before, v_before, state_out.node_q, state_out.node_qd, m.node_inv_mass,
                       self.collision.node_length, self._body_face, dt, CONTACT_REACH, self._held, self._source,
                       self._sources], device=dev)
        if int(self._sources.numpy()[0]) == 0:
            return None
        if self.serial_region:  # one CPU thread searches, and the sweeps visit only what it found
            launch(contact_region, dim=1,
                   inputs=[self._neighbour_offsets, self._neighbour_nodes, self._source, self._held, CONTACT_RINGS,
                           self._color_offsets, self._colored, self._depth, self._queue, self._resolved,
                           self._contact_offsets, self._contact_nodes], device=dev)
        else:  # a thread per node, ring after ring; the sweeps run over every node
            buffers = (self._depth, self._queue)
            for ring in range(CONTACT_RINGS):
                launch(spread_region, dim=m.node_count,
                       inputs=[self._neighbour_offsets, self._neighbour_nodes,
                               self._source if ring == 0 else buffers[(ring - 1) % 2], self._held, buffers[ring % 2],
                               self._resolved], device=dev)
        launch(contact_resolve_start, dim=m.node_count,
               inputs=[state_in.node_q, state_out.node_q, state_out.node_qd, m.node_inv_mass, self._resolved, dt,
                       self._contact_inv_mass, self._d], device=dev)
        if self.serial_region:
            launch_workers(self._descent.sweep_workers, self.workers, self._sync,
                           [CONTACT_SWEEPS, self._contact_offsets, self._no_omegas, self._contact_nodes,
                            self._contact_terms, state_in.node_q, dt, self._d, self._d_previous, self._d_before], dev)
        else:  # the nodes out of the region have no inverse mass here and stay
            self._sweep_by_colour(state_in.node_q, dt, self._contact_terms, CONTACT_SWEEPS, np.zeros(0))
        launch(contact_resolved_velocity, dim=m.node_count,
               inputs=[state_in.node_q, state_out.node_q, self._d, self._resolved, dt, state_out.node_qd], device=dev)
        return self._resolved

    def _solve(self, state_in: State, state_out: State, control: Control, dt: float) -> None:
        """The implicit solve, from state_in to v* in state_out: launches only, no host reads,
        so that it can be recorded once as a graph and replayed. With several :attr:`workers`
        (CPU threads, :func:`~party.launch.launch_workers`) the sweeps are one launch per
        thread instead, and nothing is recorded: a CPU graph replays on one thread."""
        m = self.model
        dev = m.device
        if self._planes:
            launch_items(body_planes, 0, m.node_count,
                         [self.collision.body_contact_face, m.collider_faces, state_in.collider_q,
                          state_in.collider_qd, state_in.node_q, m.node_thickness, self.collision.body_faces,
                          self.collision.body_face_count, dt, self._plane_normal, self._plane_offset,
                          self.collision.body_solve_push], dev)
        launch(inertial_target, dim=m.node_count,
               inputs=[state_in.node_q, state_in.node_qd, m.node_inv_mass, self._f_ext, m.gravity,
                       control.kinematic_velocity, self._correction, self._plane_normal, dt],
               outputs=[self._y, self._d], device=dev)
        if self._sliding:
            launch(slip_in_world, dim=m.hinge_count,
                   inputs=[state_in.node_q, m.hinge_nodes, m.hinge_friction, state_in.hinge_slip, self._slip_world],
                   device=dev)
        wp.copy(self._d_before, self._d)
        if self.workers > 1:
            launch_workers(self._descent.sweep_workers, self.workers, self._sync,
                           [self.sweeps(dt), self._color_offsets, self._omegas(dt)[1], self._colored, self._terms,
                            state_in.node_q, dt, self._d, self._d_previous, self._d_before], dev)
        else:
            self._sweep_by_colour(state_in.node_q, dt, self._terms, self.sweeps(dt), self._omegas(dt)[0])
        if self._planes:
            launch(onto_planes, dim=m.node_count, inputs=[self._terms, state_in.node_q, self._d], device=dev)
            launch(self._descent.plane_reactions, dim=m.node_count,
                   inputs=[self._terms, state_in.node_q, dt, self._d], device=dev)
        launch(record_correction, dim=m.node_count,
               inputs=[self._d, self._y, self._terms.plane_push, dt, self._correction], device=dev)
        launch(step_velocity, dim=m.node_count, inputs=[state_in.node_q, self._d, dt],
               outputs=[state_out.node_q, state_out.node_qd], device=dev)

    def _sweep_by_colour(self, x_start: wp.array, dt: float, terms: DescentTerms, sweeps: int,
                         omegas: np.ndarray) -> None:
        """``sweeps`` sweeps of the block descent on ``terms`` as one launch per colour and, with
        Chebyshev's ``omegas`` (none where empty), one per blend (on one CPU thread, recorded
        into the solve's graph, or on CUDA; several CPU threads take ``sweep_workers`` of
        :mod:`.descent` instead)."""
        offsets = self.color_offsets
        dev = self.model.device
        for iteration in range(sweeps):
            for c in range(len(offsets) - 1):
                launch(self._descent.block_descent, offsets[c + 1] - offsets[c],
                       [offsets[c], self._colored, terms, x_start, dt, self._d], device=dev)
            if len(omegas) == 0:
                continue
            if iteration == 0:
                wp.copy(self._d_previous, self._d)
                continue
            launch(chebyshev_blend, dim=self.model.node_count,
                   inputs=[self._d, self._d_previous, self._d_before, float(omegas[iteration]), self._plane_normal],
                   device=dev)

    def _descent_terms(self) -> DescentTerms:
        """The solver's and model's arrays that the block descent reads (set once; the struct
        is packed anew only where a field is replaced)."""
        m = self.model
        terms = DescentTerms()
        terms.y, terms.mass, terms.inv_mass = self._y, m.node_mass, m.node_inv_mass
        terms.neighbour_offsets, terms.neighbour_nodes = self._neighbour_offsets, self._neighbour_nodes
        terms.neighbour_params, terms.bend_diagonal = self._neighbour_params, self._bend_diagonal
        terms.tri_offsets, terms.tri_slots, terms.tris = self._tri_offsets, self._tri_slots, m.triangle_nodes
        terms.inv_rest, terms.membrane_area, terms.membrane_c = (m.triangle_inv_rest, m.triangle_membrane_area,
                                                                 m.triangle_membrane_c)
        terms.slider_offsets, terms.slider_slots = self._slider_offsets, self._slider_slots
        terms.hinge_nodes, terms.hinge_weights = m.hinge_nodes, m.hinge_weights
        terms.hinge_friction, terms.hinge_slip_limit = m.hinge_friction, m.hinge_slip_limit
        terms.slip_world = self._slip_world
        terms.plane_normal, terms.plane_offset = self._plane_normal, self._plane_offset
        terms.plane_push = (self.collision.body_solve_push if self._planes
                            else wp.zeros(m.node_count, dtype=wp.vec3, device=m.device))
        return terms


def chebyshev_weights(iterations: int, rho: float) -> np.ndarray:
    """Chebyshev's omega for each sweep after the first (Wang 2015), float32 as the kernels
    take it: omega_1 = 2 / (2 - rho^2), omega_k = 4 / (4 - rho^2 omega_{k-1}); entry 0 is
    unused. Empty for rho = 0 (no acceleration)."""
    if rho <= 0.0:
        return np.zeros(0, np.float32)
    weights = np.zeros(iterations, np.float64)
    omega = 1.0
    for k in range(1, iterations):
        omega = 2.0 / (2.0 - rho * rho) if k == 1 else 4.0 / (4.0 - rho * rho * omega)
        weights[k] = omega
    return weights.astype(np.float32)


class NeighbourRows(NamedTuple):
    """Each node's neighbours through its elements and its row of the bending matrix L, stored
    node by node (CSR ``offsets`` and ``nodes``), each entry's ``params`` (rest length [m],
    stiffness [N/m], damping [kg/s], L_ij [N/m]): one entry per element, L_ij given to the first
    element of its pair, and one more for each neighbour of L alone (no element: 0, 0, 0, L_ij);
    and L's diagonal, ``bend_diagonal`` [N/m]. A node's descent reads each neighbour once for
    its springs and its bending (a net's element neighbours are all in its bending row)."""

    offsets: np.ndarray
    nodes: np.ndarray
    params: np.ndarray
    bend_diagonal: np.ndarray


def node_neighbours(model: Model, bend) -> NeighbourRows:
    """The :class:`NeighbourRows` of ``model``'s elements and its bending matrix ``bend`` (SciPy CSR)."""
    h = model.host
    n = model.node_count
    e = h.elements.astype(np.int64)
    element_params = np.stack([h.element_rest_length, h.element_stiffness, h.element_damping], axis=1)
    rows = np.concatenate([e[:, 0], e[:, 1]])
    other = np.concatenate([e[:, 1], e[:, 0]])
    params = np.zeros((rows.size, 4))
    params[:, :3] = np.concatenate([element_params, element_params])
    coo = bend.tocoo()
    off_diagonal = coo.row != coo.col
    bend_rows, bend_cols = coo.row[off_diagonal].astype(np.int64), coo.col[off_diagonal].astype(np.int64)
    bend_values = coo.data[off_diagonal]
    pair_keys, first = np.unique(rows * n + other, return_index=True)
    bend_keys = bend_rows * n + bend_cols
    at = np.searchsorted(pair_keys, bend_keys)
    paired = at < pair_keys.size
    paired[paired] = pair_keys[at[paired]] == bend_keys[paired]
    np.add.at(params[:, 3], first[at[paired]], bend_values[paired])
    alone = ~paired
    rows = np.concatenate([rows, bend_rows[alone]])
    other = np.concatenate([other, bend_cols[alone]])
    extra = np.zeros((int(alone.sum()), 4))
    extra[:, 3] = bend_values[alone]
    params = np.concatenate([params, extra])
    offsets, order = csr_order(rows, n)
    return NeighbourRows(offsets.astype(np.int32), other[order].astype(np.int32), params[order],
                         np.asarray(bend.diagonal(), np.float64))


def slider_stiffness(model: Model) -> float:
    """The largest stuck bending stiffness L_ii / m_i [1/s^2] over the nodes of stencils with a
    bending-hysteresis slider (L the bending matrix with the sliders stuck,
    ``Model.bending_matrix(friction=True)``; 0 without hysteresis)."""
    h = model.host
    sliding = h.hinge_friction > 0.0
    if not sliding.any():
        return 0.0
    nodes = np.unique(h.hinge_nodes[sliding])
    nodes = nodes[~h.kinematic[nodes]]
    stuck = model.bending_matrix(friction=True).diagonal()
    return float(np.max(stuck[nodes] / h.mass[nodes], initial=0.0))


@dataclass(frozen=True)
class NodeCoupling:
    """How strongly each node is held by its own elements and coupled to its neighbours, per
    node: the stiffness on its diagonal, K_ii [N/m] (springs, bending L_ii and membrane
    triangles, A C_max |grad N_i|^2 with C_max the largest eigenvalue of the plane-stress
    stiffness and N_i the node's shape function), a bound on the stiffness coupling it to the
    others, sum_j |K_ij| [N/m] (springs, |L_ij|, and for membrane triangles an estimate, their
    diagonal share again), the dampers' c [kg/s] (diagonal and coupling alike), and the mass
    [kg]; free nodes only."""

    diagonal: np.ndarray
    off_diagonal: np.ndarray
    damping: np.ndarray
    mass: np.ndarray

    @classmethod
    def of(cls, model: Model, bend) -> "NodeCoupling":
        """The coupling of ``model``'s free nodes, ``bend`` its bending matrix L (SciPy CSR)."""
        h = model.host
        n = model.node_count
        e = h.elements.astype(np.int64)
        k, c = h.element_stiffness, h.element_damping
        springs = np.bincount(e[:, 0], k, n) + np.bincount(e[:, 1], k, n)
        damping = np.bincount(e[:, 0], c, n) + np.bincount(e[:, 1], c, n)
        bend_diagonal = bend.diagonal()
        bend_off = np.asarray(abs(bend).sum(axis=1)).ravel() - np.abs(bend_diagonal)
        membrane = np.zeros(n)
        area = model.triangle_membrane_area.numpy().astype(float)
        if np.any(area > 0.0):
            inverse = model.triangle_inv_rest.numpy().astype(float)
            grads = np.stack([-inverse[:, 0] - inverse[:, 1], inverse[:, 0], inverse[:, 1]], axis=1)
            c_max = np.linalg.eigvalsh(model.triangle_membrane_c.numpy().astype(float)).max(axis=1)
            share = (area * c_max)[:, None] * np.sum(grads * grads, axis=2)
            membrane = np.bincount(h.triangles.reshape(-1), share.reshape(-1), n)
        free = ~h.kinematic
        diagonal = springs + bend_diagonal + membrane
        coupling = springs + bend_off + membrane
        return cls(diagonal[free], coupling[free], damping[free], h.mass[free].astype(float))

    def largest_rate(self) -> float:
        """The largest K_ii / m_i [1/s^2] (0 without free nodes)."""
        return float(np.max(self.diagonal / self.mass, initial=0.0))

    def jacobi_bound(self, dt: float) -> float:
        """A bound on the spectral radius of Jacobi sweeps on a (sub)step of ``dt`` [s], the
        largest coupling over diagonal of the step's Hessian, (sum_j |K_ij| dt^2 + c dt) /
        (m + K_ii dt^2 + c dt); Gauss-Seidel's radius is no larger where the bound is below 1
        (Stein-Rosenberg, for the springs' M-matrix-like coupling). 1 where the coupling
        outweighs (bending's |L_ij| sum to more than L_ii). Should it fall short of the true
        radius, Chebyshev's weights still converge (for real eigenvalues their polynomial stays
        below 1 in the unit interval), only more slowly."""
        if self.mass.size == 0:
            return 0.0
        coupled = self.off_diagonal * dt * dt + self.damping * dt
        return float(min(1.0, np.max(coupled / (self.mass + self.diagonal * dt * dt + self.damping * dt))))


def node_sliders(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """CSR of the bending-hysteresis elements at each node: entries stencil * 4 + the node's
    corner, for the stencils with a slider and the corners with a weight."""
    h = model.host
    nodes = h.hinge_nodes.astype(np.int64)
    corners = (h.hinge_friction[:, None] > 0.0) & (h.hinge_weights != 0.0)
    slots = np.arange(nodes.size, dtype=np.int64).reshape(nodes.shape)[corners]
    offsets, order = csr_order(nodes[corners], model.node_count)
    return offsets.astype(np.int32), slots[order].astype(np.int32)


def node_triangles(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """CSR of the membrane triangles at each node; entries are triangle * 3 + the node's corner
    (empty rows where no triangle carries a membrane)."""
    tri = model.host.triangles.astype(np.int64)
    membrane = model.host.membrane_area > 0.0
    slots = np.arange(tri.size, dtype=np.int64).reshape(-1, 3)[membrane].ravel()
    offsets, order = csr_order(tri[membrane].ravel(), model.node_count)
    return offsets.astype(np.int32), slots[order].astype(np.int32)


def color_nodes(model: Model) -> tuple[list[int], np.ndarray]:
    """Greedy colouring of the nodes so that no two of one colour share an element, a membrane
    triangle or a hinge
    (VBD's parallel Gauss-Seidel). Returns colour offsets (host) and node ids sorted by colour;
    kinematic nodes are left out."""
    import scipy.sparse as sp

    h = model.host
    n = model.node_count
    pairs = [h.elements.astype(np.int64)]
    membrane = h.triangles[h.membrane_area > 0.0].astype(np.int64)
    pairs += [membrane[:, [0, 1]], membrane[:, [1, 2]], membrane[:, [2, 0]]]
    hinge = h.hinge_nodes.astype(np.int64)
    for a in range(4):
        for b in range(a + 1, 4):
            pairs.append(hinge[:, [a, b]])
    pairs = np.concatenate(pairs) if pairs else np.zeros((0, 2), np.int64)
    adjacency = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n)).tocsr()
    adjacency = (adjacency + adjacency.T).tocsr()
    order = np.argsort(-np.diff(adjacency.indptr), kind="stable")
    colors = np.full(n, -1, np.int64)
    indptr, indices = adjacency.indptr, adjacency.indices
    for i in order.tolist():
        taken = set(colors[indices[indptr[i]:indptr[i + 1]]].tolist())
        c = 0
        while c in taken:
            c += 1
        colors[i] = c
    free = ~h.kinematic
    ids = np.flatnonzero(free)
    ids = ids[np.argsort(colors[ids], kind="stable")]
    counts = np.bincount(colors[ids], minlength=int(colors.max()) + 1 if n else 1)
    return [0] + np.cumsum(counts).tolist(), ids.astype(np.int32)
