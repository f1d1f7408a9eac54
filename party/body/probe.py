"""Inside, distance and push-out queries of points against colliders (Warp BVHs, built once)."""

from __future__ import annotations

import numpy as np
import warp as wp

from ..device import resolve
from ..launch import launch

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels


@wp.kernel
def _inside_and_distance(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), max_dist: float,
                         ignored: wp.array(dtype=int), face_parts: wp.array(dtype=int),
                         inside: wp.array(dtype=int), distance: wp.array(dtype=float)):
    """Inside: behind the nearest face, unless that face is of a body part the point passes
    through (``ignored[i] & face_parts[face]``)."""
    i = wp.tid()
    q = wp.mesh_query_point_sign_winding_number(mesh, points[i], max_dist)
    if q.result:
        p = wp.mesh_eval_position(mesh, q.face, q.u, q.v)
        distance[i] = wp.length(points[i] - p)
        if q.sign < 0.0 and (ignored[i] & face_parts[q.face]) == 0:
            inside[i] = 1


class ColliderProbe:
    """Inside and distance queries against colliders, their BVHs built once."""

    def __init__(self, colliders, device: str | None = "cpu") -> None:
        self.device = resolve(device)  # initialises Warp quietly before the first array
        self.meshes = [
            wp.Mesh(points=wp.array(c.vertices.astype(np.float32), dtype=wp.vec3, device=self.device),
                    indices=wp.array(c.faces.ravel().astype(np.int32), dtype=int, device=self.device))
            for c in colliders
        ]
        self.face_parts = [wp.array(c.face_parts(), dtype=int, device=self.device) for c in colliders]

    def inside_and_distance(self, points: np.ndarray, max_dist: float = 1.0e3,
                            ignored_parts: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """For each point [m]: inside any (closed) collider? and its distance to the nearest
        collider surface [m]. A point inside a body part it passes through (its
        ``ignored_parts`` bits, :mod:`party.body.segmentation`) is not counted inside."""
        n = len(points)
        pts = wp.array(points.astype(np.float32), dtype=wp.vec3, device=self.device)
        ignored = wp.array(np.zeros(n, np.int32) if ignored_parts is None else np.asarray(ignored_parts, np.int32),
                           dtype=int, device=self.device)
        inside = wp.zeros(n, dtype=int, device=self.device)
        nearest = np.full(n, 1.0e30)
        for mesh, parts in zip(self.meshes, self.face_parts):
            distance = wp.full(n, 1.0e30, dtype=float, device=self.device)
            launch(_inside_and_distance, dim=n, inputs=[mesh.id, pts, max_dist, ignored, parts, inside, distance],
                   device=self.device)
            nearest = np.minimum(nearest, distance.numpy())
        return inside.numpy().astype(bool), nearest

    def push_out(self, points: np.ndarray, clearance: float) -> np.ndarray:
        """Points [m] moved to ``clearance`` [m] outside the nearest collider surface where they
        are inside a collider or nearer to it than that; others unchanged."""
        points = np.asarray(points, float).copy()
        for mesh in self.meshes:
            n = len(points)
            pts = wp.array(points.astype(np.float32), dtype=wp.vec3, device=self.device)
            out = wp.zeros(n, dtype=wp.vec3, device=self.device)
            launch(_push_out, dim=n, inputs=[mesh.id, pts, float(clearance), out], device=self.device)
            points = out.numpy().astype(float)
        return points

    def penetrations(self, points: np.ndarray) -> int:
        """Number of nodes inside any collider."""
        return int(self.inside_and_distance(points)[0].sum())




@wp.kernel
def _push_out(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), clearance: float, out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    x = points[i]
    out[i] = x
    q = wp.mesh_query_point_sign_winding_number(mesh, x, 1.0e3)
    if q.result:
        p = wp.mesh_eval_position(mesh, q.face, q.u, q.v)
        d = wp.length(x - p)
        if q.sign < 0.0 or d < clearance:
            n = wp.mesh_eval_face_normal(mesh, q.face)
            out[i] = p + n * clearance
