"""The end of every step, whichever solver proposed its velocities: the plastic limit, then
Collision() (eq. 5), then the position update (eq. 4)."""

from __future__ import annotations

from typing import Callable

import numpy as np
import warp as wp

from ..collision import CollisionPipeline, CollisionSettings
from ..collision.crossing_guard import CrossingGuard
from ..errors import InvalidInput
from ..launch import launch
from ..model import Model, State
from .explicit.kernels import (PlasticLimit, advance_positions, cap_speed, next_sweep, plastic_limit,
                               plastic_limit_sweeps)
from .hysteresis import BendingHysteresis
from .limit_worklists import limit_worklists, plastic_limit_worklists

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

PLASTIC_TOLERANCE = 5.0e-5
"""Relative length beyond the plastic limit left to the next step's sweeps (0.005 %)."""
PLASTIC_SKIPS_UNCHANGED = True
"""Sweeps of the plastic limit after the first leave out the elements whose nodes no correction
has changed since the last sweep began (:func:`~party.solvers.explicit.kernels.plastic_limit`);
False sweeps every element every time, to the same result bit for bit."""
PLASTIC_OVER_RELAXATION = 1.7
"""Over-relaxation of the plastic limit's sweeps for large steps and static relaxation (see
:class:`StepEnd`)."""

ContactResolve = Callable[[State, State, wp.array, wp.array, float, bool], "wp.array | None"]
"""``resolve(state_in, state_out, x_before, v_before, dt, first)``: after a Collision() that
found ``state_out``'s start positions and velocities at ``x_before`` and ``v_before`` (the
step's first Collision() where ``first``), change ``state_out``'s velocities in place; return
an int array flagging the nodes it changed, or None where it changed none."""


class StepEnd:
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
            velocity is cancelled exactly. Above 1 (below 2), each correction is scaled by it,
            as projected successive over-relaxation does. A garment hanging from the body has
            lines of elements at their limit from shoulder to hem, and a correction spreads along
            them like diffusion, one element per sweep and both ways: at 1 the reference dress's
            large steps used all 32 sweeps (some 20 to 60 elements still beyond) every time,
            a quarter of the drape's time; at :data:`PLASTIC_OVER_RELAXATION` they stop after
            about 6, with the same rest shape (final energy within 2 %). Over-relaxed elements
            end a little shorter than their limit where the correction overshot. Only the
            limit before Collision() is over-relaxed: the one after works against the body's
            response where a garment is tighter than the body, and over-relaxed there it threw
            a node of GarmentCode's pencil dress 5 cm out from the waist and back every
            0.5 s, its elements at 2.6 times rest.
        limit_after_contact: Enforce the plastic limit once more after Collision(), then run
            Collision() once more. The collision response (friction, and the position
            correction along the body normal) may undo a limit correction of a node in contact;
            at the paper's dt the loss is negligible, but over a large step it lets cloth in
            contact stretch step after step (seen: 27 % beyond rest in 30 steps of 1/300 s).
            The second Collision() takes up where the first left off, leaving out what it left
            settled and the limit did not change (bit for bit the same), and searches again
            where the limit moved a node out of the region searched: without, the reference
            dress once fell through the dress form in implicit steps (it came to rest on it
            with), and GarmentCode's jumpsuit, sewn tight, ended with 16 nodes inside the body
            (6 with).
        max_speed: Static relaxation's speed cap [m/s], applied to the plastic limit's
            velocities as well, so that no node moves farther than ``max_speed * dt`` in one
            iteration and Collision() sees every step. (Seams merged after sewing left some
            elements at four times their length; the limit moved their nodes 150 mm in one
            step, beyond the collision search, and 36 of them ended inside the shoulders.)
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
        self.plastic_over_relaxation = float(plastic_over_relaxation)
        self.max_speed = max_speed
        self.collision = CollisionPipeline(model, collision) if collision is not None else None
        self.plastic_passes = plastic_passes
        self._over_limit = wp.zeros(1, dtype=int, device=model.device)
        self._moved_in = wp.zeros(model.node_count, dtype=int, device=model.device)
        self._sweep_number = wp.zeros(1, dtype=int, device=model.device)
        self._moving_colliders = bool(np.any(model.collider_velocity != 0.0))
        self._has_limit = len(model.element_colored) > 0
        self._limit = plastic_limit_of(model)
        self._serial = wp.get_device(model.device).is_cpu
        self._worklists = limit_worklists(model) if self._has_limit and self._serial else None  # CPU sweeps only
        self.limit_after_contact = limit_after_contact and self._has_limit and self.collision is not None
        # without cloth collision no Collision() stops a node against another layer
        self.contact_resolve = contact_resolve if self.collision is not None and self.collision.has_cloth else None
        self.contact_rounds = max(int(contact_rounds), 1)
        if self.contact_resolve is not None:
            self._x_before = wp.zeros(model.node_count, dtype=wp.vec3, device=model.device)
            self._v_before = wp.zeros(model.node_count, dtype=wp.vec3, device=model.device)
        guarded = collision is not None and collision.cloth and collision.crossing_guard and model.triangle_count > 0
        self.guard = CrossingGuard(model, collision.guard_every) if guarded else None
        self.hysteresis = BendingHysteresis(model)

    @property
    def carried(self) -> tuple[str, ...]:
        """The plastic limit's worklists' marks, counted on from step to step
        (:mod:`party.solvers.memory`)."""
        return ("_worklists.queued", "_worklists.epoch") if self._worklists is not None else ()

    def finish(self, state_in: State, state_out: State, dt: float) -> None:
        """``state_out`` holds r(t) and v*; leave r(t + dt) and v(t + dt) there."""
        m = self.model
        dev = m.device
        if self._has_limit:
            self._apply_plastic_limit(state_out, dt, self.plastic_over_relaxation)
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
            if self._has_limit:
                self._apply_plastic_limit(state_out, dt, over_relaxation=1.0)
            else:
                self._moved_in.zero_()
            if resolved is not None:
                launch(mark_also, dim=m.node_count, inputs=[self._moved_in, resolved], device=dev)
            self._collide(state_in, state_out, dt, continuing=True,
                          changed=self._moved_in if self.max_speed is None else None)
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

    def _apply_plastic_limit(self, state: State, dt: float, over_relaxation: float = 1.0) -> int:
        """Gauss-Seidel sweeps over the element colours until a sweep finds no element beyond
        its limit (to :data:`PLASTIC_TOLERANCE`), at most ``plastic_passes`` sweeps, each
        correction scaled by ``over_relaxation``. Caps the speeds at ``max_speed`` after, where
        one is set. Returns the number of sweeps.

        On the CPU every sweep runs in one launch of one thread (:func:`plastic_limit_sweeps`;
        with :data:`PLASTIC_SKIPS_UNCHANGED`, over worklists: :mod:`.limit_worklists`):
        Warp runs a CPU launch's threads one after another anyway, so that is the same sweeps as
        one launch per colour, without the launches and the read of the count between sweeps
        (some 15 us per launch, which made the plastic limit a third of a garment drape's time;
        and a large step of a garment at rest may take all the sweeps: GarmentCode's flare dress
        takes 32 in both limits of every step of its implicit drape, and one launch and read a
        sweep had cost 0.85 ms of its 18 ms steps). Sweeps after the first leave out the
        elements whose nodes no correction has changed since the last sweep began
        (:func:`limit_element`): the same sweeps, bit for bit, over the few elements still at
        work. The nodes any correction changed are non-zero in ``_moved_in``."""
        m = self.model
        self._moved_in.zero_()
        if self._serial:
            fields = [state.node_q, state.node_qd, dt, float(over_relaxation), int(self.plastic_passes), self._moved_in,
                      self._sweep_number]
            if PLASTIC_SKIPS_UNCHANGED:
                launch(plastic_limit_worklists, dim=1, inputs=[self._limit, self._worklists, *fields], device=m.device)
            else:
                launch(plastic_limit_sweeps, dim=1, inputs=[self._limit, *fields], device=m.device)
            sweeps = int(self._sweep_number.numpy()[0])
        else:
            sweeps = self._sweep_by_colour(state, dt, over_relaxation)
        if self.max_speed is not None:
            launch(cap_speed, dim=m.node_count, inputs=[state.node_qd, float(self.max_speed)], device=m.device)
        return sweeps

    def _sweep_by_colour(self, state: State, dt: float, over_relaxation: float) -> int:
        """The plastic limit's sweeps as one launch per colour (CUDA), reading the count of
        elements beyond after each sweep; returns the number of sweeps."""
        m = self.model
        offsets = m.element_color_offsets
        sweeps = 0
        self._sweep_number.zero_()
        while sweeps < self.plastic_passes:
            sweeps += 1
            launch(next_sweep, dim=1, inputs=[self._sweep_number, self._over_limit], device=m.device)
            for offset, count in zip(offsets[:-1], np.diff(offsets)):
                launch(plastic_limit, dim=int(count),
                       inputs=[self._limit, int(offset), state.node_q, state.node_qd, dt, float(over_relaxation),
                               self._sweep_number, self._moved_in, self._over_limit], device=m.device)
            if int(self._over_limit.numpy()[0]) == 0:
                break
        return sweeps


@wp.kernel
def mark_also(flags: wp.array(dtype=int), more: wp.array(dtype=int)):
    """Set ``flags[i]`` where ``more[i]`` is set."""
    i = wp.tid()
    if more[i] != 0:
        flags[i] = 1


def plastic_limit_of(model: Model) -> PlasticLimit:
    """The arrays and settings of ``model``'s plastic limit that every sweep reads."""
    limit = PlasticLimit()
    limit.colored, limit.elem_nodes = model.element_colored, model.element_nodes
    limit.max_length, limit.inv_mass = model.element_max_length, model.node_inv_mass
    limit.tolerance, limit.skip_unchanged = PLASTIC_TOLERANCE, int(PLASTIC_SKIPS_UNCHANGED)
    return limit
