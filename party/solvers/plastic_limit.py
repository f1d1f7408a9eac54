"""The paper's plastic limit f_plas (section 5): no element elongates beyond (1 + L_sh) times its
rest length. It is a velocity constraint: an element whose length at the end of the step would
pass its limit has the relative velocity that stretches it cancelled, split by inverse mass;
elements are coloured so that one colour is processed at once, and sweeps repeat (Gauss-Seidel)
until no element would pass its limit."""

from __future__ import annotations

import numpy as np
import warp as wp

from ..errors import InvalidInput
from ..launch import launch
from ..model import Model, State
from .explicit.kernels import LimitArrays, cap_speed, next_sweep, plastic_limit, plastic_limit_sweeps
from .limit_worklists import limit_worklists, plastic_limit_worklists

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

TOLERANCE = 5.0e-5
"""Relative length beyond the plastic limit left to the next step's sweeps (0.005 %)."""

OVER_RELAXATION = 1.7
"""Over-relaxation of the sweeps for large steps and static relaxation: a garment hanging from
the body has lines of elements at their limit from shoulder to hem, along which exact
corrections spread one element per sweep, both ways; over-relaxed (as projected successive
over-relaxation does) they reach the tolerance in a fraction of the sweeps, with the same rest
shape. Over-relaxed elements end a little shorter than their limit where a correction overshot."""


class PlasticLimit:
    """The plastic limit of ``model``'s elements, in at most ``passes`` sweeps a call.

    Args:
        model: The model.
        passes: Most sweeps over the element colours per call (sweeps stop as soon as no element
            is beyond its limit, to :data:`TOLERANCE`).
        serial: Run every sweep in one launch of one thread (the CPU's way, default there:
            Warp runs a CPU launch's threads one after another anyway, so that is the same
            sweeps as one launch per colour, without the launches and the read of the count
            between sweeps), or one launch per colour reading the count after each sweep
            (CUDA's way).
        skip_unchanged: Sweeps after the first leave out the elements whose nodes no correction
            has changed since the last sweep began (on the CPU over worklists,
            :mod:`.limit_worklists`): the same sweeps, bit for bit, over the few elements still
            at work. False sweeps every element every time.
    """

    def __init__(self, model: Model, passes: int = 32, *, serial: bool | None = None,
                 skip_unchanged: bool = True) -> None:
        self.model = model
        self.passes = passes
        self.serial = wp.get_device(model.device).is_cpu if serial is None else serial
        self.active = len(model.element_colored) > 0
        self.arrays = limit_arrays(model, skip_unchanged)
        self.moved = wp.zeros(model.node_count, dtype=int, device=model.device)
        """Non-zero at the nodes any correction of the last call changed."""
        self._over_limit = wp.zeros(1, dtype=int, device=model.device)
        self._sweep_number = wp.zeros(1, dtype=int, device=model.device)
        self.worklists = limit_worklists(model) if self.active and self.serial else None

    @property
    def carried(self) -> tuple[str, ...]:
        """The worklists' marks, counted on from call to call (:mod:`party.solvers.memory`)."""
        return ("worklists.queued", "worklists.epoch") if self.worklists is not None else ()

    def apply(self, state: State, dt: float, over_relaxation: float = 1.0, max_speed: float | None = None) -> int:
        """Sweep the elements of ``state`` (its positions and the step's proposed velocities)
        until none is beyond its limit at the end of a step of ``dt`` [s], each correction
        scaled by ``over_relaxation`` (1 to 2; 1 is the paper's f_plas); cap the speeds at
        ``max_speed`` [m/s] after, where one is given. Returns the number of sweeps."""
        if not 1.0 <= over_relaxation < 2.0:
            raise InvalidInput(f"plastic over-relaxation must be in [1, 2), got {over_relaxation}")
        m = self.model
        self.moved.zero_()
        if self.serial:
            fields = [state.node_q, state.node_qd, dt, float(over_relaxation), int(self.passes), self.moved,
                      self._sweep_number]
            if self.worklists is not None and self.arrays.skip_unchanged:
                launch(plastic_limit_worklists, dim=1, inputs=[self.arrays, self.worklists, *fields], device=m.device)
            else:
                launch(plastic_limit_sweeps, dim=1, inputs=[self.arrays, *fields], device=m.device)
            sweeps = int(self._sweep_number.numpy()[0])
        else:
            sweeps = self._sweep_by_colour(state, dt, over_relaxation)
        if max_speed is not None:
            launch(cap_speed, dim=m.node_count, inputs=[state.node_qd, float(max_speed)], device=m.device)
        return sweeps

    def _sweep_by_colour(self, state: State, dt: float, over_relaxation: float) -> int:
        """The sweeps as one launch per colour, reading the count of elements beyond after each
        sweep; returns the number of sweeps."""
        m = self.model
        offsets = m.element_color_offsets
        sweeps = 0
        self._sweep_number.zero_()
        while sweeps < self.passes:
            sweeps += 1
            launch(next_sweep, dim=1, inputs=[self._sweep_number, self._over_limit], device=m.device)
            for offset, count in zip(offsets[:-1], np.diff(offsets)):
                launch(plastic_limit, dim=int(count),
                       inputs=[self.arrays, int(offset), state.node_q, state.node_qd, dt, float(over_relaxation),
                               self._sweep_number, self.moved, self._over_limit], device=m.device)
            if int(self._over_limit.numpy()[0]) == 0:
                break
        return sweeps


def limit_arrays(model: Model, skip_unchanged: bool = True) -> LimitArrays:
    """The arrays and settings of ``model``'s plastic limit that every sweep reads."""
    limit = LimitArrays()
    limit.colored, limit.elem_nodes = model.element_colored, model.element_nodes
    limit.max_length, limit.inv_mass = model.element_max_length, model.node_inv_mass
    limit.tolerance, limit.skip_unchanged = TOLERANCE, int(skip_unchanged)
    return limit
