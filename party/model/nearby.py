"""Which nodes lie within a distance of each other along the net at rest."""

from __future__ import annotations

import numpy as np

from .csr import csr_order


def nodes_within(elements: np.ndarray, rest_length: np.ndarray, radius: np.ndarray,
                 node_count: int) -> tuple[np.ndarray, np.ndarray]:
    """For each node i, the other nodes reachable from it along elements whose rest lengths
    [m] add up to less than ``radius[i]`` [m] (shortest paths over the element graph, found by
    rounds of vectorised relaxation from the pairs the last round reached or shortened);
    returned as CSR (offsets, node ids)."""
    empty = (np.zeros(node_count + 1, np.int32), np.zeros(0, np.int32))
    if len(elements) == 0 or not np.any(radius > 0.0):
        return empty
    tail = np.concatenate([elements[:, 0], elements[:, 1]]).astype(np.int64)
    head = np.concatenate([elements[:, 1], elements[:, 0]]).astype(np.int64)
    length = np.concatenate([rest_length, rest_length]).astype(np.float64)
    offsets, order = csr_order(tail, node_count)
    head, length = head[order], length[order]

    source = np.arange(node_count, dtype=np.int64)
    node = source.copy()
    distance = np.zeros(node_count)
    frontier = np.ones(node_count, bool)  # pairs reached or shortened last round: only they can lead further
    while frontier.any():
        grow = np.flatnonzero(frontier)
        degree = offsets[node[grow] + 1] - offsets[node[grow]]
        parent = np.repeat(grow, degree)
        edge = np.repeat(offsets[node[grow]] - (np.cumsum(degree) - degree), degree) + np.arange(len(parent))
        reached = distance[parent] + length[edge]
        keep = reached < radius[source[parent]]
        pairs_source = np.concatenate([source, source[parent][keep]])
        pairs_node = np.concatenate([node, head[edge][keep]])
        pairs_distance = np.concatenate([distance, reached[keep]])
        key = pairs_source * node_count + pairs_node
        best = np.lexsort((pairs_distance, key))  # by pair, shortest first; a tie keeps the known one
        first = np.ones(len(best), bool)
        first[1:] = key[best][1:] != key[best][:-1]
        best = best[first]
        frontier = best >= len(node)
        source, node, distance = pairs_source[best], pairs_node[best], pairs_distance[best]
    other = node != source
    offsets, order = csr_order(source[other], node_count)
    return offsets.astype(np.int32), node[other][order].astype(np.int32)
