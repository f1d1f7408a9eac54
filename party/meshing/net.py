"""The elastic net of the paper (section 5, figure 3) as flat-pattern arrays.

A :class:`ClothNet` holds nodes in the flat pattern plane (metres, warp along +u), the
elements joining them and the triangles used for collision and rendering. Element kinds:
warp and weft (the paper's 4-neighbour net), and shear diagonals that carry a fabric's shear
stiffness (dropped for fabrics without one, such as the paper's). Bending lives on stencils
along the threads and on the grid's quads (:func:`party.meshing.hinges.hinges`).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from ..errors import InvalidInput


class ElementKind(IntEnum):
    WARP = 0
    WEFT = 1
    SHEAR = 2


@dataclass(frozen=True)
class ClothNet:
    """A flat elastic net.

    Attributes:
        uv: Node positions in the flat pattern [m], shape (n, 2); u runs along the warp.
        elements: Node pairs (i, k), shape (m, 2), int.
        kinds: :class:`ElementKind` per element, shape (m,), int.
        widths: Width of fabric each element stands for [m], shape (m,): its spring constant
            is ``tensile_stiffness * width / rest_length`` and its damper's area share is
            ``width * rest_length``.
        triangles: Node triples, counter-clockwise in the uv plane, shape (t, 3), int.
        shape: (columns, rows) of the grid the net was cut from ((0, 0) for cut panels).
        warp_share: For warp and weft elements, the share cos^2(theta) of the warp's tensile
            stiffness an element at angle theta to the warp takes (the rest comes from the
            weft's); None means 1 for warp and 0 for weft elements (grid-aligned nets).
        rest_lengths: Element rest lengths [m]; None means their lengths in ``uv``. Sewn
            garments, whose merged seam nodes have one uv per panel, give them explicitly.
        triangle_uv: Each triangle corner's rest position in the flat pattern [m], shape
            (t, 3, 2); None means ``uv[triangles]``. Sewn garments, whose merged seam nodes
            have one uv per panel, give them explicitly.
    """

    uv: np.ndarray
    elements: np.ndarray
    kinds: np.ndarray
    widths: np.ndarray
    triangles: np.ndarray
    shape: tuple[int, int]
    warp_share: np.ndarray | None = None
    rest_lengths: np.ndarray | None = None
    triangle_uv: np.ndarray | None = None

    @property
    def node_count(self) -> int:
        return len(self.uv)

    def element_rest_lengths(self) -> np.ndarray:
        """Rest length of each element [m]."""
        if self.rest_lengths is not None:
            return np.asarray(self.rest_lengths, float)
        return np.linalg.norm(self.uv[self.elements[:, 1]] - self.uv[self.elements[:, 0]], axis=1)

    def element_warp_share(self) -> np.ndarray:
        """See ``warp_share``."""
        if self.warp_share is not None:
            return np.asarray(self.warp_share, float)
        return (self.kinds == ElementKind.WARP).astype(float)

    def rest_triangle_uv(self) -> np.ndarray:
        """See ``triangle_uv``."""
        if self.triangle_uv is not None:
            return np.asarray(self.triangle_uv, float)
        return self.uv[self.triangles]

    def rest_triangle_areas(self) -> np.ndarray:
        """Rest area of each triangle [m^2]."""
        p = self.rest_triangle_uv()
        e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
        return 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])

    def node_areas(self) -> np.ndarray:
        """Lumped node areas [m^2]: each triangle gives a third of its area to each corner."""
        out = np.zeros(self.node_count)
        np.add.at(out, self.triangles.ravel(), np.repeat(self.rest_triangle_areas() / 3.0, 3))
        return out


def triangle_edges(triangles: np.ndarray) -> np.ndarray:
    """The distinct edges of a triangle list, each as (smaller, larger) node index, sorted."""
    triangles = np.asarray(triangles)
    sides = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    return np.unique(np.sort(sides, axis=1), axis=0)


def rectangular_net(width: float, height: float, spacing: float) -> ClothNet:
    """A rectangle of cloth, ``width`` along the warp (u) by ``height`` along the weft (v) [m].

    Nodes sit on a square grid of the given spacing (adjusted so both sides divide evenly).
    Quads are split into two triangles along alternating diagonals so that the net has no
    preferred shear direction.
    """
    for name, value in (("width", width), ("height", height), ("spacing", spacing)):
        if not (np.isfinite(value) and value > 0):
            raise InvalidInput(f"cloth {name} must be positive and finite, got {value}")
    nu = max(int(round(width / spacing)), 1) + 1
    nv = max(int(round(height / spacing)), 1) + 1
    if nu * nv > 5_000_000:
        raise InvalidInput(f"cloth of {nu}x{nv} nodes is too large (spacing {spacing} m)")
    hu, hv = width / (nu - 1), height / (nv - 1)
    uu, vv = np.meshgrid(np.arange(nu) * hu, np.arange(nv) * hv, indexing="xy")
    uv = np.stack([uu.ravel(), vv.ravel()], axis=1)
    index = np.arange(nu * nv).reshape(nv, nu)

    # A boundary row or column stands for half a strip of fabric.
    row_share = np.ones(nv)
    row_share[[0, -1]] = 0.5
    col_share = np.ones(nu)
    col_share[[0, -1]] = 0.5

    elements, kinds, widths = [], [], []

    def add(a: np.ndarray, b: np.ndarray, kind: ElementKind, w: np.ndarray) -> None:
        elements.append(np.stack([a.ravel(), b.ravel()], axis=1))
        kinds.append(np.full(a.size, int(kind)))
        widths.append(np.broadcast_to(w, a.shape).ravel())

    add(index[:, :-1], index[:, 1:], ElementKind.WARP, (hv * row_share)[:, None])
    add(index[:-1, :], index[1:, :], ElementKind.WEFT, (hu * col_share)[None, :])
    diag = np.hypot(hu, hv)
    add(index[:-1, :-1], index[1:, 1:], ElementKind.SHEAR, np.full((nv - 1, nu - 1), 0.5 * diag))
    add(index[:-1, 1:], index[1:, :-1], ElementKind.SHEAR, np.full((nv - 1, nu - 1), 0.5 * diag))

    a, b = index[:-1, :-1].ravel(), index[:-1, 1:].ravel()
    c, d = index[1:, 1:].ravel(), index[1:, :-1].ravel()
    flip = ((np.arange(nv - 1)[:, None] + np.arange(nu - 1)[None, :]) % 2 == 1).ravel()
    tri1 = np.where(flip[:, None], np.stack([a, b, d], 1), np.stack([a, b, c], 1))
    tri2 = np.where(flip[:, None], np.stack([b, c, d], 1), np.stack([a, c, d], 1))
    triangles = np.concatenate([tri1, tri2]).astype(np.int32)

    return ClothNet(
        uv=uv,
        elements=np.concatenate(elements).astype(np.int32),
        kinds=np.concatenate(kinds).astype(np.int32),
        widths=np.concatenate(widths).astype(float),
        triangles=triangles,
        shape=(nu, nv),
    )
