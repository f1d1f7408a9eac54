"""Checks of a result, independent of the solver's own collision machinery (Warp BVHs):
nodes inside colliders, distance to colliders, body vertices through the cloth, cloth layer
crossings, elongation, the distance between two results' surfaces."""

from __future__ import annotations

import numpy as np
import warp as wp

from ..body.collider import ColliderMesh
from ..body.probe import ColliderProbe
from ..collision.geometry import edge_pierces_triangle
from ..launch import launch
from ..meshing.net import triangle_edges

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels


def collider_inside_and_distance(points: np.ndarray, collider: ColliderMesh, device: str = "cpu",
                                 max_dist: float = 1.0e3) -> tuple[np.ndarray, np.ndarray]:
    """For each point [m]: inside the (closed) collider? and its distance to the surface [m]."""
    return ColliderProbe([collider], device).inside_and_distance(points, max_dist)


def body_penetrations(points: np.ndarray, colliders, device: str = "cpu") -> int:
    """Number of nodes inside any collider."""
    return ColliderProbe(colliders, device).penetrations(points)


@wp.kernel
def _edge_crossings(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), tris: wp.array(dtype=int, ndim=2),
                    edges: wp.array(dtype=wp.vec2i), count: wp.array(dtype=int), crossed: wp.array(dtype=int)):
    e = wp.tid()
    i = edges[e][0]
    k = edges[e][1]
    query = wp.mesh_query_aabb(mesh, wp.min(points[i], points[k]), wp.max(points[i], points[k]))
    t = int(0)
    while wp.mesh_query_aabb_next(query, t):
        if edge_pierces_triangle(i, k, t, points, tris):
            wp.atomic_add(count, 0, 1)
            crossed[e] = t + 1


@wp.kernel
def _cloth_over_vertex(cloth: wp.uint64, vertices: wp.array(dtype=wp.vec3), normals: wp.array(dtype=wp.vec3),
                       reach: float, height: wp.array(dtype=float), nearest: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    height[i] = 1.0e30
    nearest[i] = vertices[i]
    found = wp.mesh_query_point_no_sign(cloth, vertices[i], reach)
    if found.result:
        q = wp.mesh_eval_position(cloth, found.face, found.u, found.v)
        height[i] = wp.dot(q - vertices[i], normals[i])
        nearest[i] = q


@wp.kernel
def _distance_to_surface(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), max_dist: float,
                         distance: wp.array(dtype=float)):
    i = wp.tid()
    distance[i] = max_dist
    found = wp.mesh_query_point_no_sign(mesh, points[i], max_dist)
    if found.result:
        distance[i] = wp.length(wp.mesh_eval_position(mesh, found.face, found.u, found.v) - points[i])


def distances_to_surface(points: np.ndarray, surface_points: np.ndarray, surface_triangles: np.ndarray,
                         device: str = "cpu", max_dist: float = 1.0e3) -> np.ndarray:
    """Each point's distance [m] to the nearest point of a triangle surface (``surface_points``
    [m], ``surface_triangles`` node ids), up to ``max_dist``. Between two results of one cloth
    the nearest node would count the net's sampling as a difference (up to half a spacing on
    the same surface); the surface does not."""
    mesh = wp.Mesh(points=wp.array(surface_points.astype(np.float32), dtype=wp.vec3, device=device),
                   indices=wp.array(surface_triangles.ravel().astype(np.int32), dtype=int, device=device))
    distance = wp.zeros(len(points), dtype=float, device=device)
    launch(_distance_to_surface, dim=len(points),
           inputs=[mesh.id, wp.array(points.astype(np.float32), dtype=wp.vec3, device=device), float(max_dist),
                   distance], device=device)
    return distance.numpy().astype(float)


def body_vertices_through(points: np.ndarray, triangles: np.ndarray, colliders, reach: float = 0.02,
                          device: str = "cpu") -> int:
    """Number of collider vertices that come through the cloth: the nearest cloth point, if
    within ``reach`` [m], lies behind the vertex along its normal and inside the collider.
    Nodes can all be outside a body while its vertices poke through the triangles between them
    (seen as skin through the cloth in pictures); zero when the cloth covers the body wherever
    it lies on it. Cloth outside the body is not counted though it lies behind a vertex: behind
    a body's vertex buried in another part of the same body (an arm mesh that runs into the
    torso at the armpit) or on a thin part's far side (an ear, under a hood)."""
    if len(triangles) == 0 or not colliders:
        return 0
    vertices = np.concatenate([c.vertices for c in colliders]).astype(np.float32)
    normals = np.concatenate([c.vertex_normals() for c in colliders]).astype(np.float32)
    cloth = wp.Mesh(points=wp.array(points.astype(np.float32), dtype=wp.vec3, device=device),
                    indices=wp.array(triangles.ravel().astype(np.int32), dtype=int, device=device))
    height = wp.zeros(len(vertices), dtype=float, device=device)
    nearest = wp.zeros(len(vertices), dtype=wp.vec3, device=device)
    launch(_cloth_over_vertex, dim=len(vertices),
           inputs=[cloth.id, wp.array(vertices, dtype=wp.vec3, device=device),
                   wp.array(normals, dtype=wp.vec3, device=device), float(reach), height, nearest], device=device)
    behind = height.numpy() < 0.0
    if not behind.any():
        return 0
    inside, _ = ColliderProbe(colliders, device).inside_and_distance(nearest.numpy()[behind].astype(float))
    return int(inside.sum())


def cloth_crossings(points: np.ndarray, triangles: np.ndarray, device: str = "cpu") -> int:
    """Number of (mesh edge, triangle) pairs of the cloth that pass through each other, edges and
    triangles sharing a node excluded: zero when no layer crosses another."""
    return crossing_edges(points, triangles, device)[0]


def crossing_edges(points: np.ndarray, triangles: np.ndarray,
                   device: str = "cpu") -> tuple[int, np.ndarray, np.ndarray]:
    """The crossing count of :func:`cloth_crossings`, the node pairs of the crossing edges and
    a triangle each of them passes through."""
    if len(triangles) == 0:
        return 0, np.zeros((0, 2), int), np.zeros(0, int)
    edges = triangle_edges(triangles)
    pts = wp.array(points.astype(np.float32), dtype=wp.vec3, device=device)
    mesh = wp.Mesh(points=pts, indices=wp.array(triangles.ravel().astype(np.int32), dtype=int, device=device))
    count = wp.zeros(1, dtype=int, device=device)
    crossed = wp.zeros(len(edges), dtype=int, device=device)
    launch(_edge_crossings, dim=len(edges),
           inputs=[mesh.id, pts, wp.array(triangles.astype(np.int32), dtype=int, device=device),
                   wp.array(edges.astype(np.int32), dtype=wp.vec2i, device=device), count, crossed], device=device)
    crossed = crossed.numpy()
    return int(count.numpy()[0]), edges[crossed > 0], crossed[crossed > 0] - 1


def max_elongation(points: np.ndarray, elements: np.ndarray, rest_length: np.ndarray, limited: np.ndarray) -> float:
    """Largest length / rest length over the plastic-limited elements (warp and weft) [-]."""
    if not limited.any():
        return 1.0
    e = elements[limited]
    length = np.linalg.norm(points[e[:, 1]] - points[e[:, 0]], axis=1)
    return float((length / rest_length[limited]).max())


def elements_beyond_limit(points: np.ndarray, elements: np.ndarray, max_length: np.ndarray,
                          tolerance: float = 0.02) -> int:
    """Number of elements longer than ``1 + tolerance`` times their plastic limit ``max_length``
    [m] (``Model.element_max_length``: 1e30 where an element has none, and for a sewn garment never
    shorter than its sewn length): the stretch the plastic limit has not taken back."""
    if len(elements) == 0:
        return 0
    length = np.linalg.norm(points[elements[:, 1]] - points[elements[:, 0]], axis=1)
    return int(np.count_nonzero(length > (1.0 + tolerance) * max_length))
