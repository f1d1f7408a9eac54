"""From a pattern to a garment: every panel meshed at one spacing, seams given equal node
counts on both sides, paired nodes listed, and the sewn (merged) net once seams are closed.

A seam whose sides differ in length is a gather: the longer side is sewn evenly onto the
shorter, its k-th node onto the shorter side's k-th, both spread evenly along their edges. The
gathering thread holds the longer side's edge at the shorter's length, so the elements along
that edge rest at the shorter side's lengths; the cloth behind the edge keeps its own and
folds, as gathered cloth does."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidInput
from ..meshing.net import ClothNet
from ..meshing.panel_mesh import PanelMesh, mesh_panel, segments_for
from ..pattern.pattern import Pattern
from .gathers import gathered_rest_lengths


@dataclass(frozen=True)
class Garment:
    """Meshed panels side by side (not yet joined) and the seams between them.

    Attributes:
        pattern: The pattern.
        spacing: Node spacing [m].
        panels: One :class:`PanelMesh` per panel, in pattern order.
        node_offsets: First garment node of each panel (and the total at the end).
        net: All panels' nets in one (unjoined) net, warp along +u of each panel.
        seam_pairs: Garment node pairs (i, k) to be sewn, shape (s, 2).
        seam_of_pair: Index into ``pattern.seams`` of each pair.
        corner_xy: Each triangle corner's position in its panel's own frame [m], shape (t, 3, 2):
            texture coordinates that survive the joining of seam nodes.
    """

    pattern: Pattern
    spacing: float
    panels: tuple[PanelMesh, ...]
    node_offsets: np.ndarray
    net: ClothNet
    seam_pairs: np.ndarray
    seam_of_pair: np.ndarray
    corner_xy: np.ndarray

    @property
    def node_count(self) -> int:
        return int(self.node_offsets[-1])

    def triangle_panel(self) -> np.ndarray:
        """Panel index of each triangle."""
        return np.repeat(np.arange(len(self.panels)), [len(p.net.triangles) for p in self.panels])

    def quality(self) -> dict:
        """Worst mesh quality over the panels (see :class:`PanelMesh`)."""
        qs = [p.quality for p in self.panels]
        return {"min_angle_deg": min(q["min_angle_deg"] for q in qs),
                "spacing_min": min(q["spacing_min"] for q in qs), "spacing_max": max(q["spacing_max"] for q in qs),
                "grain_error_deg": max(q["grain_error_deg"] for q in qs)}

    def sewn(self) -> tuple[ClothNet, np.ndarray]:
        """The garment as one net, each set of sewn-together nodes made one node.

        Returns the net and ``node_map`` (garment node -> sewn node). Elements that become a
        node joined to itself are dropped; the two boundary strips along a seam both stay (each
        stands for its own panel's fabric). Rest lengths and areas stay those of the flat panels.
        """
        n = self.node_count
        parent = np.arange(n)

        def find(i: int) -> int:
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for i, k in self.seam_pairs.tolist():
            ri, rk = find(i), find(k)
            if ri != rk:
                parent[max(ri, rk)] = min(ri, rk)
        roots = np.array([find(i) for i in range(n)])
        _, node_map = np.unique(roots, return_inverse=True)
        first = np.zeros(node_map.max() + 1, int)
        first[node_map[::-1]] = np.arange(n)[::-1]
        net = self.net
        elements = node_map[net.elements]
        keep = elements[:, 0] != elements[:, 1]
        sewn = ClothNet(uv=net.uv[first], elements=elements[keep].astype(np.int32), kinds=net.kinds[keep],
                        widths=net.widths[keep], triangles=node_map[net.triangles].astype(np.int32), shape=(0, 0),
                        warp_share=net.element_warp_share()[keep], rest_lengths=net.element_rest_lengths()[keep],
                        triangle_uv=net.rest_triangle_uv())
        return sewn, node_map


GATHER_DENSITY = 1.5
"""A gathered seam's sides get as many nodes as the longer side's length asks for, but its
shorter side's nodes no closer than the spacing over this: finer ones would shorten every
explicit step of the garment; the longer side's nodes spread out instead."""


def seam_segments(shorter: float, longer: float, spacing: float) -> int:
    """Segments on both sides of a seam of side lengths ``shorter`` and ``longer`` [m]."""
    return max(segments_for(shorter, spacing),
               min(segments_for(longer, spacing), segments_for(GATHER_DENSITY * shorter, spacing)))


def assemble(pattern: Pattern, spacing: float) -> Garment:
    """Mesh every panel of ``pattern`` at ``spacing`` [m] with matching seam node counts."""
    if not (np.isfinite(spacing) and 1e-3 <= spacing <= 0.2):
        raise InvalidInput(f"mesh spacing {spacing} m is outside 1-200 mm")
    counts: dict[tuple[str, int], int] = {}
    for seam in pattern.seams:
        la, lb = pattern.edge(seam.a).length(), pattern.edge(seam.b).length()
        n = seam_segments(min(la, lb), max(la, lb), spacing)
        counts[(seam.a.panel, seam.a.edge)] = n
        counts[(seam.b.panel, seam.b.edge)] = n
    meshes, offsets = [], [0]
    for name, panel in pattern.panels.items():
        mesh = mesh_panel(panel, spacing, {e: n for (p, e), n in counts.items() if p == name})
        meshes.append(mesh)
        offsets.append(offsets[-1] + mesh.net.node_count)
    index = {name: k for k, name in enumerate(pattern.panels)}
    pairs, owner = [], []
    for s, seam in enumerate(pattern.seams):
        a = meshes[index[seam.a.panel]].edge_nodes[seam.a.edge] + offsets[index[seam.a.panel]]
        b = meshes[index[seam.b.panel]].edge_nodes[seam.b.edge] + offsets[index[seam.b.panel]]
        if len(a) != len(b):
            raise InvalidInput(f"{seam}: sides meshed with {len(a)} and {len(b)} nodes")
        pairs.append(np.stack([a, b if seam.same_direction else b[::-1]], axis=1))
        owner.append(np.full(len(a), s))
    pairs = np.concatenate(pairs) if pairs else np.zeros((0, 2), int)
    owner = np.concatenate(owner) if owner else np.zeros(0, int)
    distinct = pairs[:, 0] != pairs[:, 1]
    pairs, owner = pairs[distinct], owner[distinct]

    nets = [m.net for m in meshes]
    shift = np.asarray(offsets[:-1])
    elements = np.concatenate([n.elements + s for n, s in zip(nets, shift)]).astype(np.int32)
    rest = gathered_rest_lengths(pattern, tuple(meshes), np.asarray(offsets), elements,
                                 np.concatenate([n.element_rest_lengths() for n in nets]))
    net = ClothNet(
        uv=np.concatenate([n.uv for n in nets]),
        elements=elements,
        kinds=np.concatenate([n.kinds for n in nets]).astype(np.int32),
        widths=np.concatenate([n.widths for n in nets]),
        triangles=np.concatenate([n.triangles + s for n, s in zip(nets, shift)]).astype(np.int32),
        shape=(0, 0),
        warp_share=np.concatenate([n.element_warp_share() for n in nets]),
        rest_lengths=rest,
    )
    corner_xy = np.concatenate([m.xy[m.net.triangles] for m in meshes])
    return Garment(pattern, float(spacing), tuple(meshes), np.asarray(offsets), net, pairs.astype(np.int64),
                   owner, corner_xy)
