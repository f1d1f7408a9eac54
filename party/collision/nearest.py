"""Keeping the nearest few candidates of an item (a node's triangles, a triangle's vertices)."""

import warp as wp


@wp.func
def keep_nearest(row: int, candidate: int, dist: float, count: int, capacity: int,
                 out: wp.array(dtype=int, ndim=2), out_distance: wp.array(dtype=float, ndim=2),
                 overflow: wp.array(dtype=int)) -> int:
    """Add ``candidate`` at ``dist`` [m] to ``row``'s list of ``count`` (at most ``capacity``);
    when full, it replaces the farthest one if nearer, and ``overflow`` counts the drop.
    Returns the new count."""
    slot = count
    if count < capacity:
        count += 1
    else:
        wp.atomic_add(overflow, 0, 1)
        slot = int(-1)
        worst = dist
        for s in range(capacity):
            if out_distance[row, s] > worst:
                worst = out_distance[row, s]
                slot = s
    if slot >= 0:
        out[row, slot] = candidate
        out_distance[row, slot] = dist
    return count
