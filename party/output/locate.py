"""Where a drape missed a quality gate: the panels its faults lie in, and whether the sewing
already had them (``"sewing"``) or the drape brought them (``"draping"``), so that a failure
reason sends a person to the stage and the panel to look at (:mod:`party.output.quality`)."""

from __future__ import annotations

from collections import Counter

import numpy as np

from .metrics import crossing_edges
from .quality import MAX_ELONGATION

NAMED = 2
"""Panels named per fault, most affected first."""


def node_panels(triangles: np.ndarray, triangle_panel: np.ndarray, node_count: int) -> np.ndarray:
    """A panel index per node: that of a triangle it is a corner of (a node sewn into a seam
    takes one of its panels'); -1 for a node of no triangle."""
    panel = np.full(node_count, -1, int)
    panel[triangles.ravel()] = np.repeat(triangle_panel, 3)
    return panel


def _named(panels, names: list[str]) -> list[str]:
    counts = Counter(int(p) for p in np.ravel(panels) if p >= 0)
    return [names[p] for p, _ in counts.most_common(NAMED)]


def locate(points: np.ndarray, sewn_points: np.ndarray, elements: np.ndarray, rest_length: np.ndarray,
           limited: np.ndarray, inside: np.ndarray, sewn_inside: np.ndarray, triangles: np.ndarray,
           crossings: tuple[int, np.ndarray, np.ndarray], triangle_panel: np.ndarray, names: list[str],
           device: str = "cpu") -> dict:
    """The summary's ``where``: for the most stretched warp/weft element, its panel and the stage
    whose result already held it beyond :data:`~party.output.quality.MAX_ELONGATION`; for the
    nodes inside the body and the crossing cloth edges at the end, their panels (an edge's and the
    triangle's it passes through) and whether the sewn garment (``sewn_points`` [m],
    ``sewn_inside``) had them too.

    ``points`` (n, 3) [m] the draped nodes; ``elements`` (e, 2), ``rest_length`` (e,) [m] and
    ``limited`` (e,) the model's elements; ``inside`` (n,) the draped nodes inside the body;
    ``crossings`` the draped cloth's :func:`~party.output.metrics.crossing_edges`;
    ``triangle_panel`` the panel index of each of ``triangles`` and ``names`` the panels'
    names."""
    panel = node_panels(triangles, triangle_panel, len(points))
    where: dict = {}
    if limited.any():
        e, rest = elements[limited], rest_length[limited]
        ratio = np.linalg.norm(points[e[:, 1]] - points[e[:, 0]], axis=1) / rest
        k = int(np.argmax(ratio))
        sewn_ratio = float(np.linalg.norm(sewn_points[e[k, 1]] - sewn_points[e[k, 0]]) / rest[k])
        where["stretched"] = {"panels": _named(panel[e[k]], names),
                              "stage": "sewing" if sewn_ratio > MAX_ELONGATION else "draping"}
    if inside.any():
        where["inside"] = {"panels": _named(panel[inside], names),
                           "stage": "sewing" if (inside & sewn_inside).any() else "draping"}
    count, edges, pierced = crossings
    if count:
        where["crossings"] = {"panels": _named(np.concatenate([panel[edges[:, 0]], triangle_panel[pierced]]), names),
                              "stage": "sewing" if crossing_edges(sewn_points, triangles, device)[0] else "draping"}
    return where
