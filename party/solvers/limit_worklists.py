"""The plastic limit's serial sweeps over worklists instead of over every element.

A step's plastic limit sweeps the elements in colour order until none is beyond its limit
(:meth:`~party.solvers.plastic_limit.PlasticLimit.apply`). After the first sweep only the
elements at a node that a correction has moved since the last sweep began can change anything
(:func:`~party.solvers.explicit.kernels.limit_element`); a garment at rest against a body keeps
some hundreds of its ten thousand elements at work for all 32 sweeps of both limits of a step,
and testing every element for that cost more than the corrections themselves.

Here a correction queues the elements at each node it moved: those of a later colour for the
sweep under way, all of them for the next. A sweep after the first visits only the elements
queued for it, colour by colour. Elements of one colour share no node, so the order within a
colour changes nothing: the sweeps are those over every element, bit for bit, and they set
the same ``moved_in`` marks.
"""

from __future__ import annotations

import numpy as np
import warp as wp

from ..model import Model
from ..model.csr import csr_order
from .explicit.kernels import LimitArrays, limit_element

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

EPOCH_LIMIT = wp.constant(1 << 30)
"""Sweep count at which the worklists' marks start again from zero (some 15 million steps of a
garment drape), well short of a 32-bit integer's range."""


@wp.struct
class LimitWorklists:
    """Where the serial sweeps keep their worklists.

    ``color_offsets``: colour c's slots of ``LimitArrays.colored`` are ``color_offsets[c]`` to
    ``color_offsets[c + 1] - 1``; ``slot_color``: the colour of each slot. ``node_slot_offsets``,
    ``node_slots``: per node (CSR) the slots of the limited elements at it. ``lists`` (2,
    slots): the slots queued for the sweeps of even and odd number, colour c's from
    ``color_offsets[c]``, ``counts`` (2, colours) of them. ``queued`` (2, slots): the sweep a
    slot was last queued for, counted on from launch to launch through ``epoch[0]``, so that
    no mark of an earlier step can pass for one of this step (cleared, with the count, once it
    passes :data:`EPOCH_LIMIT`)."""

    color_offsets: wp.array(dtype=int)
    slot_color: wp.array(dtype=int)
    node_slot_offsets: wp.array(dtype=int)
    node_slots: wp.array(dtype=int)
    lists: wp.array(dtype=int, ndim=2)
    counts: wp.array(dtype=int, ndim=2)
    queued: wp.array(dtype=int, ndim=2)
    epoch: wp.array(dtype=int)


def limit_worklists(model: Model) -> LimitWorklists:
    """Empty worklists for ``model``'s limited elements (:class:`LimitWorklists`)."""
    offsets = np.asarray(model.element_color_offsets, dtype=np.int32)
    slots = int(offsets[-1])
    colored = model.element_colored.numpy()
    node_offsets, order = csr_order(model.element_nodes.numpy()[colored].reshape(-1), model.node_count)
    slot_of_end = np.repeat(np.arange(slots, dtype=np.int32), 2)
    dev = model.device
    work = LimitWorklists()
    work.color_offsets = wp.array(offsets, dtype=int, device=dev)
    work.slot_color = wp.array(np.repeat(np.arange(len(offsets) - 1, dtype=np.int32), np.diff(offsets)),
                               dtype=int, device=dev)
    work.node_slot_offsets = wp.array(node_offsets.astype(np.int32), dtype=int, device=dev)
    work.node_slots = wp.array(slot_of_end[order], dtype=int, device=dev)
    work.lists = wp.zeros((2, max(slots, 1)), dtype=int, device=dev)
    work.counts = wp.zeros((2, max(len(offsets) - 1, 1)), dtype=int, device=dev)
    work.queued = wp.zeros((2, max(slots, 1)), dtype=int, device=dev)
    work.epoch = wp.zeros(1, dtype=int, device=dev)
    return work


@wp.func
def _queue(work: LimitWorklists, node: int, color: int, mark: int, now: int, later: int):
    """Queue the elements at ``node``, moved in sweep ``mark`` (its lists ``now``; -1 in the
    first sweep, which visits every element) by an element of colour ``color``: those of a
    later colour for this sweep, all for the next."""
    for j in range(work.node_slot_offsets[node], work.node_slot_offsets[node + 1]):
        slot = work.node_slots[j]
        c = work.slot_color[slot]
        if now >= 0 and c > color and work.queued[now, slot] != mark:
            work.queued[now, slot] = mark
            work.lists[now, work.color_offsets[c] + work.counts[now, c]] = slot
            work.counts[now, c] = work.counts[now, c] + 1
        if work.queued[later, slot] != mark + 1:
            work.queued[later, slot] = mark + 1
            work.lists[later, work.color_offsets[c] + work.counts[later, c]] = slot
            work.counts[later, c] = work.counts[later, c] + 1


@wp.func
def _visit(limit: LimitArrays, work: LimitWorklists, slot: int, color: int, x: wp.array(dtype=wp.vec3),
           v: wp.array(dtype=wp.vec3), dt: float, over_relaxation: float, sweep: int,
           moved_in: wp.array(dtype=int), mark: int, now: int, later: int) -> int:
    """:func:`limit_element` on the element in ``slot``, queueing the elements at the nodes
    it moved; returns 1 where it was beyond its limit's tolerance."""
    e = limit.colored[slot]
    pair = limit.elem_nodes[e]
    before_i = moved_in[pair[0]]
    before_k = moved_in[pair[1]]
    beyond = limit_element(limit, e, x, v, dt, over_relaxation, sweep, moved_in)
    # a mark left as it was: not moved, or moved earlier in this sweep, which queued its elements then
    if moved_in[pair[0]] != before_i:
        _queue(work, pair[0], color, mark, now, later)
    if moved_in[pair[1]] != before_k:
        _queue(work, pair[1], color, mark, now, later)
    return beyond


@wp.kernel
def plastic_limit_worklists(limit: LimitArrays, work: LimitWorklists, x: wp.array(dtype=wp.vec3),
                            v: wp.array(dtype=wp.vec3), dt: float, over_relaxation: float, max_sweeps: int,
                            moved_in: wp.array(dtype=int), sweeps: wp.array(dtype=int)):
    """Every sweep of the plastic limit in one thread (the CPU's serial launch), as
    :func:`~party.solvers.explicit.kernels.plastic_limit_sweeps` with ``skip_unchanged``, but
    visiting after the first sweep only the elements queued for it (see the module
    docstring); the number of sweeps taken goes to ``sweeps[0]``."""
    colors = work.color_offsets.shape[0] - 1
    base = work.epoch[0]
    if base > EPOCH_LIMIT:
        for slot in range(work.queued.shape[1]):
            work.queued[0, slot] = 0
            work.queued[1, slot] = 0
        base = 0
    sweep = int(0)
    while sweep < max_sweeps:
        sweep += 1
        mark = base + sweep
        now = sweep % 2
        later = 1 - now
        for c in range(colors):
            work.counts[later, c] = 0
        beyond = int(0)
        for c in range(colors):
            if sweep == 1:
                for slot in range(work.color_offsets[c], work.color_offsets[c + 1]):
                    beyond += _visit(limit, work, slot, c, x, v, dt, over_relaxation, sweep, moved_in, mark, -1,
                                     later)
            else:
                for j in range(work.counts[now, c]):
                    slot = work.lists[now, work.color_offsets[c] + j]
                    beyond += _visit(limit, work, slot, c, x, v, dt, over_relaxation, sweep, moved_in, mark, now,
                                     later)
        if beyond == 0:
            break
    work.epoch[0] = base + sweep + 2
    sweeps[0] = sweep
