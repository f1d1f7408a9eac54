"""Bodies from files (OBJ, PLY, STL, glTF via trimesh) or presets.

Units are detected from the stature (a standing adult is 1-2.5 m tall in any unit system's
numbers: 1-2.5 means metres, 100-250 centimetres, 1000-2500 millimetres) unless given; the up
axis is the longest extent unless given. The mesh is checked: it must be closed, coherently
oriented with outward normals, and of plausible size. Errors are one line naming the file.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ..errors import InvalidInput
from ..units import length_unit
from .body import Body, landmarks_from_stature
from .collider import ColliderMesh
from .dress_form import SIZES, dress_form
from .measurements import read_measurements
from .segmentation import read_segmentation

FORMATS = (".obj", ".ply", ".stl", ".glb", ".gltf", ".off")
UP_AXES = {"z": np.eye(3), "y": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),
           "x": np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])}
"""Rotations from a frame with the named up axis to ours (Z up; Y up's front, +z, becomes -y)."""

STATURE_RANGE = (1.0, 2.5)


def load_body(spec: str | Path, *, units: str | None = None, up: str | None = None, arms: bool = False) -> Body:
    """A preset dress form (``S``, ``M``, ``L``, or ``dress_form`` for M) or a mesh file."""
    name = str(spec)
    if name in SIZES or name == "dress_form":
        for flag, value in (("--body-units", units), ("--up", up)):
            if value is not None:
                raise InvalidInput(f"{flag} applies to a body mesh file; {name} is party's dress form, whose units "
                                   "and up axis are its own")
        return dress_form("M" if name == "dress_form" else name, arms=arms)
    path = Path(spec)
    if not path.exists():
        raise InvalidInput(f"{path}: body file not found (presets: {', '.join(SIZES)})")
    if path.is_dir():
        raise InvalidInput(f"{path} is a folder, not a body mesh file (expected one of {', '.join(FORMATS)})")
    if path.suffix.lower() not in FORMATS:
        raise InvalidInput(f"{path}: unknown body format {path.suffix or '(no suffix)'} "
                           f"(expected one of {', '.join(FORMATS)})")
    import trimesh

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds for a corrupt file
        raise InvalidInput(f"{path}: could not read a mesh ({type(exc).__name__}: {exc})".splitlines()[0]) from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InvalidInput(f"{path}: the file holds no triangles")
    vertices = np.asarray(mesh.vertices, float)
    faces = np.asarray(mesh.faces)
    if not np.all(np.isfinite(vertices)):
        raise InvalidInput(f"{path}: the mesh has non-finite vertex coordinates")
    extent = vertices.max(axis=0) - vertices.min(axis=0)
    up = up or "xyz"[int(np.argmax(extent))]
    if up not in UP_AXES:
        raise InvalidInput(f"unknown up axis {up!r} (expected x, y or z)")
    stature = float(extent["xyz".index(up)])
    scale = length_unit(units) if units else _detect_scale(stature, path)
    if not STATURE_RANGE[0] <= stature * scale <= STATURE_RANGE[1]:
        raise InvalidInput(f"{path}: the body is {stature * scale:.3g} m tall in {units or 'the detected units'}, "
                           f"outside {STATURE_RANGE[0]}-{STATURE_RANGE[1]} m; check --body-units and --up")
    rotation = UP_AXES[up]
    points = (vertices * scale) @ rotation.T
    collider = ColliderMesh(path.stem, points, faces, vertex_parts=read_segmentation(path, len(points)))
    if not mesh.is_watertight:
        raise InvalidInput(f"{path}: the body mesh is not closed (it has holes); close it before draping")
    marks = landmarks_from_stature(points)
    axis_sel = np.abs(points[:, 2] - marks["waist"]) < 0.05
    axis = tuple(np.median(points[axis_sel, :2], axis=0)) if axis_sel.any() else (0.0, 0.0)
    return Body(path.stem, (collider,), marks, axis=(float(axis[0]), float(axis[1])),
                to_source=rotation.T, measurements=read_measurements(path))


def _detect_scale(stature: float, path: Path) -> float:
    for unit in ("m", "cm", "mm"):
        s = length_unit(unit)
        if STATURE_RANGE[0] <= stature * s <= STATURE_RANGE[1]:
            return s
    raise InvalidInput(f"{path}: cannot tell the units of a body {stature:.4g} units tall (expected 1-2.5 m, "
                       "100-250 cm or 1000-2500 mm); pass --body-units")
