"""Cutting a panel into the paper's elastic net.

Inside the panel, nodes sit on a square grid of the requested spacing whose rows run along the
grain line, so warp and weft elements lie exactly along the grain; along the outline, each edge
gets as many evenly spaced nodes as the caller asks for (seams give both sides one count).
Grid nodes closer than ``BOUNDARY_CLEARANCE`` spacings to the outline are dropped, everything
is joined by a Delaunay triangulation clipped to the outline, and each triangle side becomes an
element: grid sides are warp or weft, grid diagonals shear, and sides at other angles near the
outline take the warp and weft stiffness in proportion to cos^2 and sin^2 of their angle to the
grain.

With ``thread_ends``, edges not seamed get their nodes where the grid's threads cross them
instead: every thread then runs straight to the outline, so bending stencils
(:mod:`party.meshing.hinges`) reach the last grid node before a free edge, and the fringe along
the edge is not left without bending stiffness (a drape specimen's overhang is short enough for
that fringe to matter).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
import shapely.ops
from scipy.spatial import Delaunay

from ..errors import InvalidInput
from ..pattern.pattern import Panel
from .net import ClothNet, ElementKind

BOUNDARY_CLEARANCE = 0.6
"""Grid nodes nearer than this many spacings to the outline are left out."""

MAX_NODES_PER_PANEL = 400_000

BIAS_FLOOR = 0.05
"""Smallest share of its straight-grain stiffness an off-grain side near the outline keeps."""


@dataclass(frozen=True)
class PanelMesh:
    """A meshed panel.

    Attributes:
        panel: The panel.
        net: The elastic net; its ``uv`` is in the grain frame (warp along +u) [m].
        xy: Node positions in the panel's own frame [m] (for placement, textures, export).
        edge_nodes: Per outline edge, its node indices from its start to its end.
        quality: ``min_angle_deg``, ``spacing_min``/``spacing_max`` (element length over the
            requested spacing), ``grain_error_deg`` (largest angle between a grid warp or weft
            element and the grain).
    """

    panel: Panel
    net: ClothNet
    xy: np.ndarray
    edge_nodes: tuple[np.ndarray, ...]
    quality: dict


def segments_for(length: float, spacing: float) -> int:
    """Segments an edge of ``length`` gets at ``spacing`` [m] (at least one)."""
    return max(int(round(length / spacing)), 1)


def mesh_panel(panel: Panel, spacing: float, segments: dict[int, int] | None = None, *,
               thread_ends: bool = False) -> PanelMesh:
    """Mesh ``panel`` at node ``spacing`` [m]; ``segments`` fixes the segment count of some
    edges (seamed edges), the others get :func:`segments_for`, or with ``thread_ends`` a node
    wherever a grid thread crosses them."""
    if not (np.isfinite(spacing) and spacing > 0):
        raise InvalidInput(f"mesh spacing must be positive, got {spacing}")
    segments = segments or {}
    grain = np.asarray(panel.grain, float) / np.hypot(*panel.grain)
    to_grain = np.array([[grain[0], grain[1]], [-grain[1], grain[0]]])  # rows: warp, weft

    if thread_ends:
        dense = np.concatenate([e.sample(max(64 * segments_for(e.length(), spacing), 64)) for e in panel.edges])
        lo, hi, _, _, offset = _grid_frame(dense @ to_grain.T, spacing, panel.name)
    ring, edge_nodes = [], []
    for k, edge in enumerate(panel.edges):
        if thread_ends and k not in segments:
            pts = _thread_crossings(edge, to_grain, offset, spacing)
        else:
            pts = edge.sample(segments.get(k) or segments_for(edge.length(), spacing))
        start = len(ring)
        ring.extend(pts[:-1])
        edge_nodes.append(np.arange(start, start + len(pts)))
    count = len(ring)
    edge_nodes = tuple(np.where(ids == count, 0, ids) for ids in edge_nodes)
    ring = np.asarray(ring)
    outline = shapely.Polygon(ring)
    if not outline.is_valid or outline.area <= 0:
        raise InvalidInput(f"panel {panel.name!r}: outline self-intersects at {spacing * 1000:.0f} mm spacing; "
                           "use a finer spacing")

    ring_g = ring @ to_grain.T
    if not thread_ends:
        lo, hi = ring_g.min(axis=0), ring_g.max(axis=0)
    lo, hi, nu, nv, offset = _grid_frame(np.array([lo, hi]), spacing, panel.name)
    gu, gv = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    grid_g = offset + spacing * np.stack([gu.ravel(), gv.ravel()], axis=1)
    grid_xy = grid_g @ to_grain  # back to the panel frame
    inside = shapely.contains_xy(outline, grid_xy[:, 0], grid_xy[:, 1])
    clear = shapely.distance(outline.exterior, shapely.points(grid_xy)) >= BOUNDARY_CLEARANCE * spacing
    keep = inside & clear
    grid_ij = np.stack([gu.ravel(), gv.ravel()], axis=1)[keep]
    xy = np.vstack([ring, grid_xy[keep]])
    uv = xy @ to_grain.T
    is_grid = np.r_[np.zeros(count, bool), np.ones(int(keep.sum()), bool)]
    ij = np.vstack([np.full((count, 2), -10**6), grid_ij])

    triangles = _clipped_delaunay(xy, outline, count, panel.name)
    elements, kinds, widths, share = _elements(uv, triangles, is_grid, ij)
    net = ClothNet(uv=uv, elements=elements, kinds=kinds, widths=widths, triangles=triangles,
                   shape=(0, 0), warp_share=share)
    return PanelMesh(panel, net, xy, edge_nodes, _quality(uv, triangles, elements, kinds, is_grid, ij, spacing))


def _grid_frame(points_g: np.ndarray, spacing: float, name: str):
    """The grid over ``points_g`` (grain frame) [m]: its bounding box, node counts along warp
    and weft, and the first node, centred in the box."""
    lo, hi = points_g.min(axis=0), points_g.max(axis=0)
    nu, nv = (np.floor((hi - lo) / spacing).astype(int) + 1)
    if nu * nv > MAX_NODES_PER_PANEL:
        raise InvalidInput(f"panel {name!r}: {nu * nv} grid nodes at {spacing * 1000:.1f} mm spacing is too many")
    offset = lo + 0.5 * ((hi - lo) - (np.array([nu, nv]) - 1) * spacing)
    return lo, hi, nu, nv, offset


THREAD_END_GAP = 0.5
"""Thread crossings of an edge closer than this many spacings to a kept one are dropped."""


def _thread_crossings(edge, to_grain: np.ndarray, offset: np.ndarray, spacing: float) -> np.ndarray:
    """Points along ``edge`` (panel frame) [m] from its start to its end where it crosses a
    thread of the grid whose first node is ``offset`` (grain frame) [m], the crossing's
    coordinate across the thread set exactly to the thread's."""
    dense = edge.sample(max(64 * segments_for(edge.length(), spacing), 64))
    g = dense @ to_grain.T
    found = [(0.0, g[0])]
    arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(dense, axis=0), axis=1))]
    for axis in (0, 1):
        index = (g[:, axis] - offset[axis]) / spacing
        for s in np.flatnonzero(np.floor(index[:-1]) != np.floor(index[1:])):
            line = float(max(np.floor(index[s]), np.floor(index[s + 1])))
            t = (line - index[s]) / (index[s + 1] - index[s])
            point = g[s] + t * (g[s + 1] - g[s])
            point[axis] = offset[axis] + line * spacing
            found.append((arc[s] + t * (arc[s + 1] - arc[s]), point))
    found.sort(key=lambda item: item[0])
    kept = [found[0]]
    for position, point in found[1:]:
        if position - kept[-1][0] >= THREAD_END_GAP * spacing and arc[-1] - position >= THREAD_END_GAP * spacing:
            kept.append((position, point))
    points = np.array([p for _, p in kept] + [g[-1]])
    return points @ to_grain


def _clipped_delaunay(xy: np.ndarray, outline: shapely.Polygon, ring_count: int, name: str) -> np.ndarray:
    tri = Delaunay(xy).simplices
    for k in _missing_outline_sides(tri, ring_count):
        tri = _recover_segment(xy, tri, k, (k + 1) % ring_count)
    p = xy[tri]
    probes = np.concatenate([p.mean(axis=1), 0.5 * (p[:, [0, 1, 2]] + p[:, [1, 2, 0]]).reshape(-1, 2)])
    region = outline.buffer(1e-9)
    ok = shapely.contains_xy(region, probes[:, 0], probes[:, 1])
    ok = ok[: len(tri)] & ok[len(tri):].reshape(-1, 3).all(axis=1)
    tri = tri[ok]
    e1, e2 = p[ok, 1] - p[ok, 0], p[ok, 2] - p[ok, 0]
    cross = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    tri = np.where((cross < 0)[:, None], tri[:, [0, 2, 1]], tri)
    tri = tri[np.abs(cross) > 1e-14]
    # Every outline segment must be a triangle side, else the net has a notch or a bridge.
    missing = _missing_outline_sides(tri, ring_count)
    if missing:
        raise InvalidInput(f"panel {name!r}: could not mesh its outline near ({xy[missing[0], 0]:.3f}, "
                           f"{xy[missing[0], 1]:.3f}) m; use a finer spacing")
    used = np.zeros(len(xy), bool)
    used[tri.ravel()] = True
    if not used.all():
        raise InvalidInput(f"panel {name!r}: a node was left out of the mesh; use a finer spacing")
    return tri.astype(np.int32)


def _missing_outline_sides(tri: np.ndarray, ring_count: int) -> list[int]:
    """Each k whose outline segment k-(k+1) (the ring's first ``ring_count`` nodes) is no side of
    a triangle of ``tri``."""
    sides = {tuple(sorted(s)) for t in tri.tolist() for s in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    return [k for k in range(ring_count) if tuple(sorted((k, (k + 1) % ring_count))) not in sides]


def _recover_segment(xy: np.ndarray, tri: np.ndarray, a: int, b: int) -> np.ndarray:
    """``tri`` with the outline segment ``a``-``b``, no side of its triangles (a node of the
    outline too near it, such as a dart's point near the panel's edge, took it out of the
    Delaunay triangulation), made one: the triangles it passes through are taken out and the
    hole on each side of it triangulated again, constrained to its boundary (Anglada's insertion
    of a segment into a Delaunay triangulation). A segment an earlier insertion made a side
    crosses no triangle, and ``tri`` comes back as it was."""
    segment = shapely.LineString(xy[[a, b]])
    polygons = shapely.polygons(xy[tri])
    crossed = shapely.relate_pattern(polygons, segment, "T********")
    if not crossed.any():
        return tri
    hole = shapely.unary_union(polygons[crossed])
    index = {tuple(np.round(q, 12)): i for i, q in enumerate(xy)}
    refilled = []
    for piece in shapely.get_parts(shapely.ops.split(hole, segment)):
        for t in shapely.get_parts(shapely.constrained_delaunay_triangles(piece)):
            corners = [index.get(tuple(np.round(q, 12))) for q in shapely.get_coordinates(t)[:3]]
            if None in corners:
                return tri
            refilled.append(corners)
    return np.vstack([tri[~crossed], np.asarray(refilled, tri.dtype).reshape(-1, 3)])


def _elements(uv, triangles, is_grid, ij):
    sides = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    p = uv[triangles]
    area = 0.5 * np.abs((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                        - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0]))
    keyed = np.sort(sides, axis=1)
    elements, inverse = np.unique(keyed, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    tri_area = np.zeros(len(elements))
    np.add.at(tri_area, inverse, np.tile(area, 3))
    d = uv[elements[:, 1]] - uv[elements[:, 0]]
    length = np.hypot(d[:, 0], d[:, 1])
    cos2 = (d[:, 0] / length) ** 2
    step = np.abs(ij[elements[:, 1]] - ij[elements[:, 0]])
    grid = is_grid[elements[:, 0]] & is_grid[elements[:, 1]]
    diagonal = grid & (step[:, 0] == 1) & (step[:, 1] == 1)
    kinds = np.where(cos2 >= 0.5, ElementKind.WARP, ElementKind.WEFT)
    kinds = np.where(diagonal, ElementKind.SHEAR, kinds).astype(np.int32)
    aligned = grid & ~diagonal & ((step[:, 0] + step[:, 1]) == 1)
    share = np.where(aligned, (kinds == ElementKind.WARP).astype(float), cos2)
    # A side's width: the fabric area of its triangles per unit length; a grid diagonal splits
    # its quad, so it stands for half the quad's diagonal (as in the rectangular net). A side
    # off the grain near the outline stands in for the warp and weft threads it crosses, which
    # resist its stretch only in proportion to cos^2(2 theta): a net of warp and weft alone
    # gives no resistance on the bias (45 degrees), and neither do these sides.
    bias = np.maximum((2.0 * cos2 - 1.0) ** 2, BIAS_FLOOR)
    widths = np.where(diagonal, 0.5 * length, tri_area / length * np.where(aligned, 1.0, bias))
    return elements.astype(np.int32), kinds, widths, share


def _quality(uv, triangles, elements, kinds, is_grid, ij, spacing) -> dict:
    p = uv[triangles]
    angles = []
    for a, b, c in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        u, w = p[:, b] - p[:, a], p[:, c] - p[:, a]
        cosang = (u * w).sum(1) / (np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1))
        angles.append(np.degrees(np.arccos(np.clip(cosang, -1, 1))))
    length = np.linalg.norm(uv[elements[:, 1]] - uv[elements[:, 0]], axis=1)
    in_plane = kinds != ElementKind.SHEAR
    grid = is_grid[elements[:, 0]] & is_grid[elements[:, 1]] & in_plane
    d = uv[elements[grid, 1]] - uv[elements[grid, 0]]
    off = np.degrees(np.minimum(np.abs(np.arctan2(d[:, 1], d[:, 0])) % np.pi,
                                np.abs(np.arctan2(d[:, 0], d[:, 1])) % np.pi))
    off = np.minimum(off, 180.0 - off)
    return {
        "nodes": int(len(uv)), "triangles": int(len(triangles)),
        "min_angle_deg": float(np.min(angles)),
        "spacing_min": float(length[in_plane].min() / spacing), "spacing_max": float(length[in_plane].max() / spacing),
        "grain_error_deg": float(off.max()) if len(off) else 0.0,
    }
