"""Bodies and props the cloth collides with, as closed triangle meshes with outward normals."""

from .collider import ColliderMesh, collider_from_trimesh
from .primitives import box, floor, rod, sphere

__all__ = ["ColliderMesh", "collider_from_trimesh", "box", "floor", "rod", "sphere"]
