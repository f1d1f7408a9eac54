"""A collider: a validated triangle mesh with per-vertex normals (section 6: "triangle
patches with normals"). Positions in metres."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh

from ..errors import InvalidInput


FLAT = 1.0e-5
"""A closed collider whose volume is below this share of its area^(3/2) is taken as flat: a
sphere's share is 0.094, a standing person's about 0.03, a plate 1 mm thick and 0.5 m across
7e-4, a body squashed onto a plane 0. Nothing can be worn on a flat one, and its neighbour
searches degenerate."""


@dataclass(frozen=True)
class ColliderMesh:
    """A body or prop, checked on construction.

    Attributes:
        name: Label used in messages.
        vertices: Vertex positions [m], shape (n, 3), float.
        faces: Triangles, counter-clockwise seen from outside, shape (t, 3), int.
        velocity: Constant linear velocity of the whole mesh [m/s], shape (3,); the surface
            velocity enters the response of eq. (12). Moving meshes may also be driven per
            step through the State.
        vertex_parts: Body-part bits of each vertex (:mod:`party.body.segmentation`), shape
            (n,) int32, 0 in none; None for a collider without parts.
    """

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    vertex_parts: np.ndarray | None = None

    def __post_init__(self) -> None:
        v = np.asarray(self.vertices, dtype=float)
        f = np.asarray(self.faces)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "velocity", np.asarray(self.velocity, dtype=float).reshape(3))
        if v.ndim != 2 or v.shape[1] != 3 or len(v) == 0 or f.size == 0:
            raise InvalidInput(f"collider {self.name!r} is empty (needs vertices and triangles)")
        if f.ndim != 2 or f.shape[1] != 3 or not np.issubdtype(f.dtype, np.integer):
            raise InvalidInput(f"collider {self.name!r}: faces must be an integer array of shape (t, 3)")
        object.__setattr__(self, "faces", f.astype(np.int32))
        if not np.all(np.isfinite(v)):
            raise InvalidInput(f"collider {self.name!r} has non-finite vertex positions")
        if f.min() < 0 or f.max() >= len(v):
            raise InvalidInput(f"collider {self.name!r} has a face index out of range [0, {len(v)})")
        if self.vertex_parts is not None:
            parts = np.asarray(self.vertex_parts, np.int32)
            if parts.shape != (len(v),):
                raise InvalidInput(f"collider {self.name!r}: {parts.size} vertex part labels for {len(v)} vertices")
            object.__setattr__(self, "vertex_parts", parts)
        self._check_manifold()

    def _check_manifold(self) -> None:
        f = self.faces
        if np.any((f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])):
            raise InvalidInput(f"collider {self.name!r} has degenerate triangles (repeated vertex)")
        area2 = np.linalg.norm(self.face_normals_unnormalized(), axis=1)
        if np.any(area2 <= 1e-14):
            raise InvalidInput(f"collider {self.name!r} has zero-area triangles")
        directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        undirected = np.sort(directed, axis=1)
        _, counts = np.unique(undirected, axis=0, return_counts=True)
        if np.any(counts > 2):
            raise InvalidInput(
                f"collider {self.name!r} is non-manifold: {int(np.sum(counts > 2))} edges are shared by more than two triangles")
        _, dcounts = np.unique(directed, axis=0, return_counts=True)
        if np.any(dcounts > 1):
            raise InvalidInput(f"collider {self.name!r} has inconsistently oriented triangles (normals not coherent)")
        if np.all(counts == 2) and self.signed_volume() < 0.0:
            raise InvalidInput(f"collider {self.name!r} has inward-facing normals (negative enclosed volume)")
        area = 0.5 * float(area2.sum())
        if np.all(counts == 2) and self.signed_volume() < FLAT * area**1.5:
            raise InvalidInput(f"collider {self.name!r} encloses almost no volume ({1000.0 * self.signed_volume():.3g} "
                               f"litres inside {area:.3g} m^2 of surface): it is flat or folded onto itself")

    def face_parts(self) -> np.ndarray:
        """Body-part bits of each face, shape (t,) int32: the parts all three corners are in."""
        if self.vertex_parts is None:
            return np.zeros(len(self.faces), np.int32)
        corners = self.vertex_parts[self.faces]
        return corners[:, 0] & corners[:, 1] & corners[:, 2]

    def vertex_part_bits(self) -> np.ndarray:
        """:attr:`vertex_parts`, zeros for a collider without parts, shape (n,) int32."""
        return np.zeros(len(self.vertices), np.int32) if self.vertex_parts is None else self.vertex_parts

    def face_normals_unnormalized(self) -> np.ndarray:
        p = self.vertices[self.faces]
        return np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])

    def signed_volume(self) -> float:
        p = self.vertices[self.faces]
        return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0)

    def vertex_normals(self) -> np.ndarray:
        """Angle-weighted vertex normals (Thuermer and Wuethrich 1998), unit, shape (n, 3):
        independent of how a flat face is split into triangles."""
        p = self.vertices[self.faces]
        fn = self.face_normals_unnormalized()
        fn /= np.linalg.norm(fn, axis=1, keepdims=True)
        vn = np.zeros_like(self.vertices)
        for corner in range(3):
            e1 = p[:, (corner + 1) % 3] - p[:, corner]
            e2 = p[:, (corner + 2) % 3] - p[:, corner]
            cos = np.einsum("ij,ij->i", e1, e2) / (np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1))
            np.add.at(vn, self.faces[:, corner], fn * np.arccos(np.clip(cos, -1, 1))[:, None])
        return vn / np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-30)

    def corner_normals(self, crease_degrees: float = 30.0) -> np.ndarray:
        """Normals at each face corner, shape (t, 3, 3): the smooth vertex normal where it is
        within ``crease_degrees`` of the face normal, else the face normal (sharp edges of a
        box or a table stay sharp, a sphere or a body stays smooth)."""
        return self._corners(crease_degrees)[0]

    def crease_normals(self, crease_degrees: float = 30.0, most: int = 4) -> np.ndarray:
        """The faces' normals met at each convex vertex on a crease, shape (n, most, 3),
        zero-padded: for a vertex where :meth:`corner_normals` keeps some corner's face normal
        (a rim, a box's edge or corner) and whose neighbours all lie on or behind each of those
        faces, their distinct normals (those within ``crease_degrees`` / 2 of one already taken
        count once; at most ``most``). Between them and the vertex normal lie the directions
        the body faces at a sharp convex vertex; a smooth or concave vertex has none."""
        normals, sharp = self._corners(crease_degrees)
        out = np.zeros((len(self.vertices), most, 3))
        if not sharp.any():
            return out
        ids, normals = self.faces[sharp], normals[sharp]
        order = np.argsort(ids, kind="stable")
        ids, normals = ids[order], normals[order]
        neighbours = self.to_trimesh().vertex_neighbors
        same = np.cos(np.radians(0.5 * crease_degrees))
        starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
        for start, stop in zip(starts, np.r_[starts[1:], len(ids)]):
            vertex = ids[start]
            ring = self.vertices[neighbours[vertex]] - self.vertices[vertex]
            if np.any(ring @ normals[start:stop].T > 1e-6 * np.linalg.norm(ring, axis=1).max()):
                continue
            taken = []
            for n in normals[start:stop]:
                if len(taken) < most and all(float(n @ t) < same for t in taken):
                    taken.append(n)
            out[vertex, :len(taken)] = taken
        return out

    def _corners(self, crease_degrees: float) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`corner_normals` and which corners took the face normal (sharp), shape (t, 3)."""
        fn = self.face_normals_unnormalized()
        fn /= np.linalg.norm(fn, axis=1, keepdims=True)
        corner = self.vertex_normals()[self.faces]
        sharp = np.einsum("tkc,tc->tk", corner, fn) < np.cos(np.radians(crease_degrees))
        return np.where(sharp[:, :, None], fn[:, None, :], corner), sharp

    def translated(self, offset) -> "ColliderMesh":
        return ColliderMesh(self.name, self.vertices + np.asarray(offset, float), self.faces, self.velocity,
                            self.vertex_parts)

    def to_trimesh(self) -> trimesh.Trimesh:
        return trimesh.Trimesh(self.vertices, self.faces, process=False)


def collider_from_trimesh(mesh: trimesh.Trimesh, name: str, velocity=(0.0, 0.0, 0.0)) -> ColliderMesh:
    """Wrap a trimesh mesh (already in metres) as a collider, validating it."""
    return ColliderMesh(name, np.asarray(mesh.vertices), np.asarray(mesh.faces), np.asarray(velocity, float))
