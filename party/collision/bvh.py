"""A bounding-volume hierarchy over triangles' swept boxes: the faster broad phase.

Section 6.1's axis interval lists walk about sqrt(N) list entries per query on a surface of
N triangles; a BVH (Warp's ``wp.Bvh``) visits about log N boxes. Both find the same
triangles: those whose box, swept over the step and grown by a margin, overlaps the node's.
"""

from __future__ import annotations

import warp as wp

from ..launch import launch
from .intervals import _item_boxes


class TriangleBvh:
    """A BVH over the boxes of ``triangles`` (int32 [t, 3]) swept from ``points`` over
    ``velocities * dt`` and grown by ``margin``; rebuilt in place by :meth:`build`."""

    def __init__(self, triangles: wp.array) -> None:
        self.triangles = triangles
        self.count = int(triangles.shape[0])
        self.device = triangles.device
        self.lower = wp.zeros(max(self.count, 1), dtype=wp.vec3, device=self.device)
        self.upper = wp.zeros(max(self.count, 1), dtype=wp.vec3, device=self.device)
        self._bounds = wp.zeros(6, dtype=float, device=self.device)
        self.bvh: wp.Bvh | None = None

    @property
    def id(self) -> wp.uint64:
        return self.bvh.id

    def forget(self) -> None:
        """Drop the tree: the next :meth:`build` makes it anew from its boxes then."""
        self.bvh = None

    def build(self, points: wp.array, velocities: wp.array, dt: float, margin: float) -> None:
        """Recompute the boxes and refit the tree (built on the first call)."""
        launch(_item_boxes, dim=self.count,
               inputs=[points, velocities, self.triangles, dt, margin, self.lower, self.upper, self._bounds],
               device=self.device)
        if self.bvh is None:
            self.bvh = wp.Bvh(self.lower, self.upper)
        else:
            self.bvh.refit()
