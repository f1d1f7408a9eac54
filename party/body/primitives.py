"""Props as closed collider meshes: a rod, a sphere, a box and a floor. Metres throughout."""

from __future__ import annotations

import numpy as np
import trimesh

from .collider import ColliderMesh, collider_from_trimesh


def rod(length: float, radius: float, *, center=(0.0, 0.0, 0.0), axis=(0.0, 1.0, 0.0),
        sections: int = 48, name: str = "rod") -> ColliderMesh:
    """A capsule: a cylinder of the given length and radius [m] with hemispherical ends, along
    ``axis``, centred at ``center``."""
    mesh = trimesh.creation.capsule(height=length, radius=radius, count=[sections, sections // 2])
    mesh.apply_transform(trimesh.geometry.align_vectors([0, 0, 1], np.asarray(axis, float)))
    mesh.apply_translation(center)
    return collider_from_trimesh(mesh, name)


def sphere(radius: float, *, center=(0.0, 0.0, 0.0), subdivisions: int = 4, name: str = "sphere") -> ColliderMesh:
    """An icosphere of the given radius [m]."""
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    mesh.apply_translation(center)
    return collider_from_trimesh(mesh, name)


def box(extents, *, center=(0.0, 0.0, 0.0), name: str = "box") -> ColliderMesh:
    """An axis-aligned box with the given edge lengths [m]."""
    mesh = trimesh.creation.box(extents=np.asarray(extents, float))
    mesh.apply_translation(center)
    return collider_from_trimesh(mesh, name)


def floor(height: float = 0.0, *, size: float = 10.0, up: int = 2, name: str = "floor") -> ColliderMesh:
    """A floor: a wide slab whose top face lies at ``height`` [m] along axis ``up``."""
    extents = np.full(3, size)
    extents[up] = 0.1
    center = np.zeros(3)
    center[up] = height - 0.05
    return box(extents, center=center, name=name)
