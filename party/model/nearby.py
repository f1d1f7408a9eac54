"""Which nodes lie within a distance of each other along the net at rest."""

from __future__ import annotations

import numpy as np


def nodes_within(elements: np.ndarray, rest_length: np.ndarray, radius: np.ndarray,
                 node_count: int) -> tuple[np.ndarray, np.ndarray]:
    """For each node i, the other nodes reachable from it along elements whose rest lengths
    [m] add up to less than ``radius[i]`` [m] (shortest paths over the element graph, Dijkstra
    by rounds of vectorised relaxation); returned as CSR (offsets, node ids)."""
    empty = (np.zeros(node_count + 1, np.int32), np.zeros(0, np.int32))
    if len(elements) == 0 or not np.any(radius > 0.0):
        return empty
    tail = np.concatenate([elements[:, 0], elements[:, 1]]).astype(np.int64)
    head = np.concatenate([elements[:, 1], elements[:, 0]]).astype(np.int64)
    length = np.concatenate([rest_length, rest_length]).astype(np.float64)
    order = np.argsort(tail, kind="stable")
    head, length = head[order], length[order]
    offsets = np.zeros(node_count + 1, np.int64)
    np.add.at(offsets, tail + 1, 1)
    offsets = np.cumsum(offsets)

    source = np.arange(node_count, dtype=np.int64)
    node = source.copy()
    distance = np.zeros(node_count)
    while True:
        degree = offsets[node + 1] - offsets[node]
        parent = np.repeat(np.arange(len(node)), degree)
        edge = offsets[node][parent] + np.arange(len(parent)) - np.repeat(np.cumsum(degree) - degree, degree)
        reached = distance[parent] + length[edge]
        keep = reached < radius[source[parent]]
        pairs_source = np.concatenate([source, source[parent][keep]])
        pairs_node = np.concatenate([node, head[edge][keep]])
        pairs_distance = np.concatenate([distance, reached[keep]])
        key = pairs_source * node_count + pairs_node
        best = np.lexsort((pairs_distance, key))
        first = np.ones(len(best), bool)
        first[1:] = key[best][1:] != key[best][:-1]
        best = best[first]
        if len(best) == len(node) and np.array_equal(pairs_distance[best], distance):  # both in key order
            break
        source, node, distance = pairs_source[best], pairs_node[best], pairs_distance[best]
    other = node != source
    rows, ids = source[other], node[other]
    counts = np.bincount(rows, minlength=node_count)
    return np.concatenate([[0], np.cumsum(counts)]).astype(np.int32), ids.astype(np.int32)
