"""Gathered seams: the longer side of a seam sewn evenly onto the shorter.

Along the seam a gathering thread holds the longer side's edge at the shorter side's length;
behind it the cloth folds into gathers that fan out into the flat panel. A net at garment
spacing cannot fold within a centimetre, and where its rows near the seam keep their flat
lengths they push the seam open, stretching the shorter side (a cuff, a waistband) far beyond
its rest. So the gathered panel is shirred: each element near the seam rests shorter along the
seam's direction, by the seam's ratio at the seam and less with distance from it, back to its
own length at :data:`GATHER_DEPTH` of the length the gather takes up. The cloth rests as the
puff that gathers make (a sleeve gathered into a cuff, a skirt into a waistband); its mass and
its length across the seam are the flat panel's. Sides that differ by less than :data:`EASED`
are eased, not gathered, and keep their rest lengths.
"""

from __future__ import annotations

import numpy as np
import shapely

from ..meshing.panel_mesh import PanelMesh
from ..pattern.pattern import Pattern

EASED = 1.1
"""A side up to this much longer than the other is eased in, not gathered (a sleeve cap into its
armhole, a bodice into a waist seam, by a few percent): the cloth takes that in its own plane,
as wool steamed into a sleeve cap does, so its rest lengths stay those of the flat panel."""

GATHER_DEPTH = 0.5
"""How far from a gathered seam its shirring reaches, as a fraction of the length the gather
takes up (longer side minus shorter) [-]: a sleeve of 46 cm gathered into a cuff of 18 cm puffs
over some 14 cm, a sleeve cap eased by 2 cm only along its edge."""


def gathered_rest_lengths(pattern: Pattern, meshes: tuple[PanelMesh, ...], offsets: np.ndarray,
                          elements: np.ndarray, rest: np.ndarray) -> np.ndarray:
    """``rest`` [m] (one per element of the garment's unjoined net, ``elements`` its garment
    node pairs) with every gathered seam's longer side shirred (see the module docstring)."""
    rest = np.array(rest, float)
    index = {name: k for k, name in enumerate(pattern.panels)}
    for seam in pattern.seams:
        la, lb = pattern.edge(seam.a).length(), pattern.edge(seam.b).length()
        if max(la, lb) < EASED * min(la, lb):
            continue
        longer = seam.a if la > lb else seam.b
        ratio = max(la, lb) / min(la, lb)
        k = index[longer.panel]
        mesh = meshes[k]
        local = (elements >= offsets[k]) & (elements < offsets[k + 1])
        inside = np.flatnonzero(local.all(axis=1))
        pairs = elements[inside] - offsets[k]
        edge = shapely.LineString(mesh.xy[mesh.edge_nodes[longer.edge]])
        depth = GATHER_DEPTH * abs(la - lb)
        a, b = mesh.xy[pairs[:, 0]], mesh.xy[pairs[:, 1]]
        middle = shapely.points(0.5 * (a + b))
        distance = shapely.distance(edge, middle)
        near = distance < max(depth, 1e-9) + 1e-9
        if not near.any():
            continue
        tangent = _tangent(edge, middle[near])
        vector = (b - a)[near] / np.linalg.norm(b - a, axis=1)[near, None] * rest[inside[near], None]
        along = np.einsum("ij,ij->i", vector, tangent)
        across = vector - along[:, None] * tangent
        keep = 1.0 - (1.0 - 1.0 / ratio) * np.clip(1.0 - distance[near] / max(depth, 1e-9), 0.0, 1.0)
        rest[inside[near]] = np.hypot(keep * along, np.linalg.norm(across, axis=1))
    return rest


def _tangent(line: shapely.LineString, points: np.ndarray) -> np.ndarray:
    """Unit tangent of ``line`` at its nearest point to each of ``points``, shape (n, 2)."""
    at = shapely.line_locate_point(line, points)
    step = 1e-4 * max(line.length, 1e-9)
    ahead = shapely.get_coordinates(shapely.line_interpolate_point(line, np.minimum(at + step, line.length)))
    behind = shapely.get_coordinates(shapely.line_interpolate_point(line, np.maximum(at - step, 0.0)))
    tangent = ahead - behind
    return tangent / np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-12)
