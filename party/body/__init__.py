"""Bodies and props the cloth collides with, as closed triangle meshes with outward normals."""

from .body import Body
from .collider import ColliderMesh, collider_from_trimesh
from .dress_form import SIZES, Measurements, dress_form
from .load import load_body
from .primitives import box, floor, rod, sphere

__all__ = ["Body", "ColliderMesh", "Measurements", "SIZES", "box", "collider_from_trimesh", "dress_form", "floor",
           "load_body", "rod", "sphere"]
