"""The end of every step, whichever solver proposed its velocities v*: the paper's velocity
filters, the plastic limit and Collision() (eq. 5), then the position update (eq. 4), and ours
after it, the crossing guard and the bending hysteresis's slips."""

from __future__ import annotations

from typing import Callable

import numpy as np
import warp as wp

from ..collision import CollisionPipeline, CollisionSettings
from ..collision.crossing_guard import CrossingGuard
from ..errors import InvalidInput
from ..launch import launch
from ..model import Model, State
from .explicit.kernels import advance_positions
from .hysteresis import BendingHysteresis
from .plastic_limit import PlasticLimit

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

ContactResolve = Callable[[State, State, wp.array, wp.array, float, bool], "wp.array | None"]
"""``resolve(state_in, state_out, x_before, v_before, dt, first)``: after a Collision() that
found ``state_out``'s start positions and velocities at ``x_before`` and ``v_before`` (the
step's first Collision() where ``first``), change ``state_out``'s velocities in place; return
an int array flagging the nodes it changed, or None where it changed none."""


class StepFilters:
    """Filters proposed velocities v* and moves the nodes:

        v* <- f_plas(v*)                 plastic limit (section 5, figure 5)
        v(t + dt) = Collision(v*)        (5)
        r(t + dt) = r(t) + v(t + dt) dt  (4)
        crossing guard                   (ours; :mod:`party.collision.crossing_guard`)
        bending hysteresis slips         (ours; :mod:`party.solvers.hysteresis`)

    Args:
        model: The model.
        collision: Collision settings (section 6); ``None`` switches collision off.
        plastic_passes: Most sweeps over the element colours per step enforcing the plastic
            limit (sweeps stop as soon as no element is beyond it).
        plastic_over_relaxation: 1 applies the paper's f_plas: each element's stretching
            velocity is cancelled exactly; above 1 (below 2) each correction is scaled by it
            (:data:`~party.solvers.plastic_limit.OVER_RELAXATION`). Only the limit before
            Collision() is over-relaxed: the one after works against the body's response where
            a garment is tighter than the body, and over-relaxed there it throws nodes in and
            out.
        limit_after_contact: Enforce the plastic limit once more after Collision(), then run
            Collision() once more. The collision response (friction, and the position
            correction along the body normal) may undo a limit correction of a node in contact;
            at the paper's dt the loss is negligible, but over a large step it lets cloth in
            contact stretch step after step. The second Collision() takes up where the first
            left off, leaving out what it left settled and the limit did not change (bit for
            bit the same), and searches again where the limit moved a node out of the region
            searched.
        max_speed: Static relaxation's speed cap [m/s], applied to the plastic limit's
            velocities as well, so that no node moves farther than ``max_speed * dt`` in one
            iteration and Collision() sees every step: a limit correcting an element far beyond
            its length would otherwise move its nodes beyond the collision search.
        contact_resolve: Called after every Collision() of a step but its last
            (:data:`ContactResolve`; only with cloth collision): the implicit solver solves
            again there for the cloth around the nodes Collision() stopped. The plastic limit
            and Collision() follow each call, so that Collision() keeps the last word.
        contact_rounds: Most calls of ``contact_resolve`` a step, each followed by the limit
            and Collision(). A call that changes nothing ends the rounds, but for the first,
            whose limit and Collision() run anyway with ``limit_after_contact``.
    """

    def __init__(self, model: Model, collision: CollisionSettings | None, plastic_passes: int,
                 limit_after_contact: bool = False, max_speed: float | None = None,
                 plastic_over_relaxation: float = 1.0, contact_resolve: ContactResolve | None = None,
                 contact_rounds: int = 1) -> None:
        if not 1.0 <= plastic_over_relaxation < 2.0:
            raise InvalidInput(f"plastic over-relaxation must be in [1, 2), got {plastic_over_relaxation}")
        self.model = model
        self.limit = PlasticLimit(model, plastic_passes)
        self.plastic_over_relaxation = float(plastic_over_relaxation)
        self.max_speed = max_speed
        self.collision = CollisionPipeline(model, collision) if collision is not None else None
        self._moving_colliders = bool(np.any(model.collider_velocity != 0.0))
        self.limit_after_contact = limit_after_contact and self.limit.active and self.collision is not None
        # without cloth collision no Collision() stops a node against another layer
        self.contact_resolve = contact_resolve if self.collision is not None and self.collision.has_cloth else None
        self.contact_rounds = max(int(contact_rounds), 1)
        self._unlimited = wp.zeros(model.node_count, dtype=int, device=model.device)
        if self.contact_resolve is not None:
            self._x_before = wp.zeros(model.node_count, dtype=wp.vec3, device=model.device)
            self._v_before = wp.zeros(model.node_count, dtype=wp.vec3, device=model.device)
        guarded = collision is not None and collision.cloth and collision.crossing_guard and model.triangle_count > 0
        self.guard = CrossingGuard(model, collision.guard_every, collision.guard) if guarded else None
        self.hysteresis = BendingHysteresis(model)

    def finish(self, state_in: State, state_out: State, dt: float) -> None:
        """``state_out`` holds r(t) and v*; leave r(t + dt) and v(t + dt) there."""
        m = self.model
        dev = m.device
        if self.limit.active:
            self.limit.apply(state_out, dt, self.plastic_over_relaxation, self.max_speed)
        wp.copy(state_out.collider_q, state_in.collider_q)
        wp.copy(state_out.collider_qd, state_in.collider_qd)
        if self.collision is not None:
            self._collide(state_in, state_out, dt)
        resolving = self.contact_resolve is not None
        for round_ in range(self.contact_rounds if resolving else int(self.limit_after_contact)):
            resolved = self.contact_resolve(state_in, state_out, self._x_before, self._v_before, dt,
                                            round_ == 0) if resolving else None
            if resolved is None and (round_ > 0 or not self.limit_after_contact):
                break  # the last Collision() stands: it moved no node's end enough for a round
            if self.limit.active:
                self.limit.apply(state_out, dt, 1.0, self.max_speed)
                changed = self.limit.moved
            else:
                self._unlimited.zero_()
                changed = self._unlimited
            if resolved is not None:
                launch(mark_also, dim=m.node_count, inputs=[changed, resolved], device=dev)
            self._collide(state_in, state_out, dt, continuing=True,
                          changed=changed if self.max_speed is None else None)
        launch(advance_positions, dim=m.node_count, inputs=[state_out.node_q, state_out.node_qd, dt], device=dev)
        if self.guard is not None:
            self.guard.apply(state_in.node_q, state_out.node_q, state_out.node_qd)
        if self._moving_colliders:
            launch(advance_positions, dim=len(state_out.collider_q),
                   inputs=[state_out.collider_q, state_out.collider_qd, dt], device=dev)
        self.hysteresis.update(state_in, state_out)
        state_out.time = state_in.time + dt

    def _collide(self, state_in: State, state_out: State, dt: float, **continuation) -> None:
        """Collision() on ``state_out`` (eq. 5), recording its start positions and velocities
        before for :attr:`contact_resolve`."""
        if self.contact_resolve is not None:
            wp.copy(self._x_before, state_out.node_q)
            wp.copy(self._v_before, state_out.node_qd)
        self.collision.apply(state_out.node_q, state_out.node_qd, state_in, dt, **continuation)

    def flush(self, state: State) -> None:
        """Run a crossing check that the guard's interval has left pending, so that ``state``
        may be output or measured."""
        if self.guard is not None and self.guard.pending:
            self.guard.check(state.node_q, state.node_qd)

@wp.kernel
def mark_also(flags: wp.array(dtype=int), more: wp.array(dtype=int)):
    """Set ``flags[i]`` where ``more[i]`` is set."""
    i = wp.tid()
    if more[i] != 0:
        flags[i] = 1
