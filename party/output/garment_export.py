"""Writing a sewn garment with its pattern texture coordinates: OBJ (with ``vt``) and glTF
binary (.glb). Seam nodes are shared by two panels with different pattern coordinates, so the
written mesh has one vertex per (node, panel); positions are metres in whatever frame the
caller passes (the body file's frame, see :meth:`party.body.Body.to_file_frame`). Texture
coordinates are the flat pattern's, in metres, so a texture tiles at a known physical size.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import trimesh


def split_by_panel(points: np.ndarray, triangles: np.ndarray, triangle_panel: np.ndarray,
                   corner_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One vertex per (node, panel): returns vertices (v, 3), faces (t, 3), uv (v, 2) and the
    node of each vertex (v,)."""
    keys = np.stack([triangles.ravel(), np.repeat(triangle_panel, 3)], axis=1)
    unique, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    node = unique[:, 0]
    uv = corner_xy.reshape(-1, 2)[first]
    return points[node], inverse.reshape(-1, 3).astype(np.int64), uv, node


def write_garment(out: Path, stem: str, points: np.ndarray, triangles: np.ndarray, triangle_panel: np.ndarray,
                  corner_xy: np.ndarray) -> list[Path]:
    """Write ``out/STEM.obj`` (with UVs) and ``out/STEM.glb``; returns the paths."""
    vertices, faces, uv, _ = split_by_panel(points, triangles, triangle_panel, corner_xy)
    mesh = trimesh.Trimesh(vertices, faces, process=False, visual=trimesh.visual.TextureVisuals(uv=uv))
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for suffix in ("obj", "glb"):
        path = out / f"{stem}.{suffix}"
        data = mesh.export(file_type=suffix, include_normals=True) if suffix == "obj" else mesh.export(file_type=suffix)
        tmp = path.with_name(path.name + ".part")
        tmp.write_bytes(data.encode() if isinstance(data, str) else data)
        os.replace(tmp, path)
        paths.append(path)
    return paths
