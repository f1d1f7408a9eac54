"""Axis interval lists (section 6.1, figure 6).

The bounding box of a set of triangles is cut along X, Y and Z into intervals; each axis keeps
the list of triangles whose extent overlaps each interval. A query box (the box spanned by a
node's position r and r + dr, grown by the thickness) selects a run of intervals on each
axis; with n_x, n_y, n_z list entries found there, only the axis with n = min(n_x, n_y, n_z)
is walked, each triangle once, and each is box-checked in 3-D before the exact test.

The lists are rebuilt on the device each step (count, prefix sum, fill), so moving bodies and
the cloth itself (for cloth-cloth collision) use the same structure. Triangle boxes cover the
triangle at the start and at the end of the step, so the lists are valid for the whole step.
"""

from __future__ import annotations

import numpy as np
import warp as wp

from ..errors import PartyError
from ..launch import launch
from .geometry import boxes_overlap

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels


@wp.struct
class IntervalLists:
    """Device view of the lists. ``bounds`` holds (lo.x, lo.y, lo.z, hi.x, hi.y, hi.z) [m];
    ``cell`` the interval length per axis [m]; ``cells`` the interval count per axis;
    ``offsets[axis * (max_cells + 1) + c]`` the start of interval c of an axis in ``ids``."""

    bounds: wp.array(dtype=float)
    cell: wp.array(dtype=float)
    cells: wp.array(dtype=int)
    offsets: wp.array(dtype=int)
    ids: wp.array(dtype=int)
    item_lo: wp.array(dtype=wp.vec3)
    item_hi: wp.array(dtype=wp.vec3)
    max_cells: int


@wp.func
def cell_of(lists: IntervalLists, axis: int, value: float) -> int:
    c = int(wp.floor((value - lists.bounds[axis]) / lists.cell[axis]))
    return wp.clamp(c, 0, lists.cells[axis] - 1)


@wp.func
def query_axis(lists: IntervalLists, lo: wp.vec3, hi: wp.vec3) -> wp.vec3i:
    """The axis with the fewest list entries under the box, and its interval run (axis, c0, c1).
    An empty result has c1 < c0."""
    best = wp.vec3i(0, 1, 0)
    best_n = int(2147483647)
    for axis in range(3):
        if hi[axis] < lists.bounds[axis] or lo[axis] > lists.bounds[axis + 3]:
            return wp.vec3i(axis, 1, 0)
        c0 = cell_of(lists, axis, lo[axis])
        c1 = cell_of(lists, axis, hi[axis])
        base = axis * (lists.max_cells + 1)
        n = lists.offsets[base + c1 + 1] - lists.offsets[base + c0]
        if n < best_n:
            best_n = n
            best = wp.vec3i(axis, c0, c1)
    return best


@wp.func
def found_once(lists: IntervalLists, item: int, lo: wp.vec3, hi: wp.vec3, axis: int, c0: int, c: int) -> bool:
    """Whether a walk of intervals ``c0`` on along ``axis`` that meets ``item`` in interval ``c``
    finds it: its box meets the query box ``lo``..``hi`` and ``c`` is the one interval of the
    walk where it is first listed (no repeats). The box is tested first: it rejects most of a
    slab's entries, and costs less than the first interval's division."""
    if not boxes_overlap(lo, hi, lists.item_lo[item], lists.item_hi[item]):
        return False
    return wp.max(cell_of(lists, axis, lists.item_lo[item][axis]), c0) == c


@wp.kernel
def _item_boxes(points: wp.array(dtype=wp.vec3), velocities: wp.array(dtype=wp.vec3),
                tris: wp.array(dtype=int, ndim=2), dt: float, margin: float,
                item_lo: wp.array(dtype=wp.vec3), item_hi: wp.array(dtype=wp.vec3),
                bounds: wp.array(dtype=float)):
    t = wp.tid()
    lo = wp.vec3(1.0e30)
    hi = wp.vec3(-1.0e30)
    for k in range(3):
        p = points[tris[t, k]]
        q = p + velocities[tris[t, k]] * dt
        lo = wp.min(lo, wp.min(p, q))
        hi = wp.max(hi, wp.max(p, q))
    lo = lo - wp.vec3(margin)
    hi = hi + wp.vec3(margin)
    item_lo[t] = lo
    item_hi[t] = hi
    for a in range(3):
        wp.atomic_min(bounds, a, lo[a])
        wp.atomic_max(bounds, a + 3, hi[a])


@wp.kernel
def _layout(bounds: wp.array(dtype=float), min_cell: float, max_cells: int,
            cell: wp.array(dtype=float), cells: wp.array(dtype=int)):
    for a in range(3):
        extent = wp.max(bounds[a + 3] - bounds[a], 1.0e-6)
        size = wp.max(min_cell, extent / float(max_cells))
        cell[a] = size
        cells[a] = wp.clamp(int(wp.ceil(extent / size)), 1, max_cells)


@wp.kernel
def _count(lists: IntervalLists, counts: wp.array(dtype=int)):
    t = wp.tid()
    for a in range(3):
        c0 = cell_of(lists, a, lists.item_lo[t][a])
        c1 = cell_of(lists, a, lists.item_hi[t][a])
        for c in range(c0, c1 + 1):
            wp.atomic_add(counts, a * (lists.max_cells + 1) + c, 1)


@wp.kernel
def _scan(counts: wp.array(dtype=int), offsets: wp.array(dtype=int), cursor: wp.array(dtype=int),
          capacity: int, overflow: wp.array(dtype=int)):
    total = int(0)
    for j in range(counts.shape[0]):
        offsets[j] = total
        cursor[j] = total
        total += counts[j]
        counts[j] = 0
    offsets[counts.shape[0]] = total
    if total > capacity:
        overflow[0] = total


@wp.kernel
def _fill(lists: IntervalLists, cursor: wp.array(dtype=int), capacity: int):
    t = wp.tid()
    for a in range(3):
        c0 = cell_of(lists, a, lists.item_lo[t][a])
        c1 = cell_of(lists, a, lists.item_hi[t][a])
        for c in range(c0, c1 + 1):
            slot = wp.atomic_add(cursor, a * (lists.max_cells + 1) + c, 1)
            if slot < capacity:
                lists.ids[slot] = t


@wp.kernel
def _reset_bounds(bounds: wp.array(dtype=float)):
    a = wp.tid()
    if a < 3:
        bounds[a] = 1.0e30
    else:
        bounds[a] = -1.0e30


class AxisIntervalLists:
    """Interval lists over a fixed set of triangles whose vertices may move.

    Args:
        triangles: Vertex indices, int32 array of shape [t, 3] on the device.
        min_cell: Smallest interval length [m]; intervals are at least this long, so a
            triangle smaller than it spans at most two intervals per axis.
        max_cells: Largest number of intervals per axis.
    """

    def __init__(self, triangles: wp.array, *, min_cell: float, max_cells: int = 256,
                 spans_per_item: int = 4) -> None:
        self.device = triangles.device
        self.triangles = triangles
        self.count = triangles.shape[0]
        self.max_cells = max_cells
        self.min_cell = float(min_cell)
        self.capacity = max(3 * spans_per_item * self.count, 1)
        dev = self.device
        self._counts = wp.zeros(3 * (max_cells + 1), dtype=int, device=dev)
        self._cursor = wp.zeros(3 * (max_cells + 1), dtype=int, device=dev)
        self._overflow = wp.zeros(1, dtype=int, device=dev)
        self.lists = IntervalLists()
        self.lists.bounds = wp.zeros(6, dtype=float, device=dev)
        self.lists.cell = wp.zeros(3, dtype=float, device=dev)
        self.lists.cells = wp.zeros(3, dtype=int, device=dev)
        self.lists.offsets = wp.zeros(3 * (max_cells + 1) + 1, dtype=int, device=dev)
        self.lists.ids = wp.zeros(self.capacity, dtype=int, device=dev)
        self.lists.item_lo = wp.zeros(max(self.count, 1), dtype=wp.vec3, device=dev)
        self.lists.item_hi = wp.zeros(max(self.count, 1), dtype=wp.vec3, device=dev)
        self.lists.max_cells = max_cells

    def build(self, points: wp.array, velocities: wp.array, dt: float, margin: float) -> None:
        """Rebuild for triangles moving from ``points`` with ``velocities`` over ``dt``; boxes
        are grown by ``margin`` [m]. Launches only (no host sync), so it can be captured."""
        if self.count == 0:
            return
        L, dev = self.lists, self.device
        launch(_reset_bounds, dim=6, inputs=[L.bounds], device=dev)
        launch(_item_boxes, dim=self.count,
               inputs=[points, velocities, self.triangles, dt, margin, L.item_lo, L.item_hi, L.bounds], device=dev)
        launch(_layout, dim=1, inputs=[L.bounds, self.min_cell, self.max_cells, L.cell, L.cells], device=dev)
        launch(_count, dim=self.count, inputs=[L, self._counts], device=dev)
        launch(_scan, dim=1, inputs=[self._counts, L.offsets, self._cursor, self.capacity, self._overflow], device=dev)
        launch(_fill, dim=self.count, inputs=[L, self._cursor, self.capacity], device=dev)

    def grow_if_needed(self) -> bool:
        """After a build: if the lists overflowed, enlarge them (x1.5 headroom) and return True
        so the caller rebuilds. Syncs with the device; call between steps, not inside one."""
        needed = int(self._overflow.numpy()[0])
        if not needed:
            return False
        if needed > 200_000_000:
            raise PartyError(f"collision interval lists would need {needed} entries; the geometry is degenerate")
        self.capacity = int(needed * 1.5) + 16
        self.lists.ids = wp.zeros(self.capacity, dtype=int, device=self.device)
        self._overflow.zero_()
        return True

    def build_checked(self, points: wp.array, velocities: wp.array, dt: float, margin: float) -> None:
        """:meth:`build`, growing the capacity until everything fits (syncs)."""
        self.build(points, velocities, dt, margin)
        while self.grow_if_needed():
            self.build(points, velocities, dt, margin)

    def host_lists(self) -> dict:
        """The lists on the host, for tests and inspection."""
        L = self.lists
        return {
            "bounds": L.bounds.numpy(), "cell": L.cell.numpy(), "cells": L.cells.numpy(),
            "offsets": L.offsets.numpy(), "ids": L.ids.numpy(),
            "item_lo": L.item_lo.numpy(), "item_hi": L.item_hi.numpy(), "max_cells": self.max_cells,
        }


@wp.kernel
def _broad_phase_candidates(lists: IntervalLists, lo: wp.array(dtype=wp.vec3), hi: wp.array(dtype=wp.vec3),
                            max_out: int, out: wp.array(dtype=int, ndim=2), out_count: wp.array(dtype=int),
                            rule_n: wp.array(dtype=int)):
    q = wp.tid()
    sel = query_axis(lists, lo[q], hi[q])
    axis = sel[0]
    base = axis * (lists.max_cells + 1)
    if sel[2] >= sel[1]:
        rule_n[q] = lists.offsets[base + sel[2] + 1] - lists.offsets[base + sel[1]]
    found = int(0)
    for c in range(sel[1], sel[2] + 1):
        for j in range(lists.offsets[base + c], lists.offsets[base + c + 1]):
            item = lists.ids[j]
            if not found_once(lists, item, lo[q], hi[q], axis, sel[1], c):
                continue
            if found < max_out:
                out[q, found] = item
            found += 1
    out_count[q] = found


def broad_phase(structure: AxisIntervalLists, lo: np.ndarray, hi: np.ndarray, max_out: int = 4096):
    """Candidates for query boxes ``lo``..``hi`` (host arrays [q, 3]): returns a list of index
    arrays and the n = min(n_x, n_y, n_z) count each query walked. For tests and tools."""
    dev = structure.device
    q = len(lo)
    out = wp.zeros((q, max_out), dtype=int, device=dev)
    count = wp.zeros(q, dtype=int, device=dev)
    rule = wp.zeros(q, dtype=int, device=dev)
    launch(_broad_phase_candidates, dim=q,
           inputs=[structure.lists, wp.array(lo.astype(np.float32), dtype=wp.vec3, device=dev),
                   wp.array(hi.astype(np.float32), dtype=wp.vec3, device=dev), max_out, out, count, rule],
           device=dev)
    out, count = out.numpy(), count.numpy()
    return [out[k, : min(count[k], max_out)] for k in range(q)], rule.numpy()
