"""How far each vertex of a collider stands out of the surface around it (set-up, NumPy).

Cloth held a thickness eps off a body can still meet one of its vertices between the cloth's
nodes where the body bends more tightly than the cloth's triangles are long (an arm under a
20 mm net, a rim, a sharp corner); :mod:`party.collision.body_vertices` tests those. Over a
large, smooth body (a sphere of 0.3 m under a 16 mm net) no vertex can come near the cloth
over it, and the test is work for nothing. :func:`vertex_relief` gives, per vertex, what
decides it: how far the vertex rises along its normal above the body within a reach, and how
far the surface there turns from its normal. Lengths in metres.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .collider import ColliderMesh

MAX_PAIRS = 2_000_000
"""Most (vertex, neighbour) pairs held at once: the searches run over chunks of vertices sized
to it, so that their memory is bounded whatever the reach (some 100 MB)."""


def vertex_relief(collider: ColliderMesh, reach: float, *, enough: np.ndarray | float = np.inf,
                  max_pairs: int = MAX_PAIRS) -> tuple[np.ndarray, np.ndarray]:
    """Per vertex p with unit normal n_p, over the body's surface points q within ``reach`` [m]
    of p: the largest rise max (p - q) . n_p [m] (the exact maximum over each triangle cut by
    the ball: its corners inside, its edges' crossings of the sphere and the point of its plane's
    circle farthest down), and the smallest cosine between n_p and the normals of the
    triangles cut.

    A vertex whose rise over the vertices alone reaches ``enough`` [m] (a scalar or one value
    per vertex) is reported with that rise, and with the cosine over those vertices' normals;
    its triangles are not clipped: the caller only needs to know that it rises that far. The
    searches hold about ``max_pairs`` (vertex, neighbour) pairs at a time."""
    points = collider.vertices
    normals = collider.vertex_normals()
    count = len(points)
    enough = np.broadcast_to(np.asarray(enough, dtype=float), (count,))
    rise = np.zeros(count)
    cosine = np.ones(count)
    tree = cKDTree(points)
    open_ = np.arange(count)
    for radius in (reach / 4.0, reach / 2.0, reach):  # most vertices of a body rise far enough early
        for chunk in _chunks(open_, points, tree, radius, max_pairs):
            near = cKDTree(points[chunk]).sparse_distance_matrix(tree, radius, output_type="ndarray")
            owner, other = chunk[near["i"]], near["j"].astype(np.int64)
            np.maximum.at(rise, owner, np.einsum("ij,ij->i", points[owner] - points[other], normals[owner]))
            np.minimum.at(cosine, owner, np.einsum("ij,ij->i", normals[other], normals[owner]))
        open_ = open_[rise[open_] < enough[open_]]
        if len(open_) == 0:
            return rise, cosine
    corners = points[collider.faces]
    face_normals = collider.face_normals_unnormalized()
    face_normals /= np.linalg.norm(face_normals, axis=1, keepdims=True)
    for chunk in _chunks(open_, points, tree, reach, max_pairs):
        vertex, face = _faces_near(points[chunk], corners, reach)
        vertex = chunk[vertex]
        height, cut = _lowest_in_ball(points[vertex], normals[vertex], corners[face], face_normals[face], reach)
        np.maximum.at(rise, vertex[cut], height[cut])
        np.minimum.at(cosine, vertex[cut], np.einsum("ij,ij->i", face_normals[face[cut]], normals[vertex[cut]]))
    return rise, cosine


def _chunks(chosen: np.ndarray, points: np.ndarray, tree: cKDTree, radius: float, max_pairs: int) -> list[np.ndarray]:
    """``chosen`` (vertex indices) cut into chunks whose neighbours within ``radius`` number
    about ``max_pairs`` at most, judged from the densest of a sample of the vertices."""
    if len(chosen) == 0:
        return []
    sample = chosen[np.linspace(0, len(chosen) - 1, min(len(chosen), 64)).astype(np.int64)]
    most = int(np.max(tree.query_ball_point(points[sample], radius, return_length=True)))
    size = max(1, max_pairs // max(4 * most, 1))
    return [chosen[k:k + size] for k in range(0, len(chosen), size)]


def _faces_near(points: np.ndarray, corners: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (point, face) whose face may come within ``reach`` of the point: those whose
    bounding sphere about the centroid does (the few faces far larger than most, met by
    every point, apart)."""
    centroid = corners.mean(axis=1)
    radius = np.linalg.norm(corners - centroid[:, None], axis=2).max(axis=1)
    small = radius <= 2.0 * np.median(radius)
    ids = np.flatnonzero(small)
    near = cKDTree(points).sparse_distance_matrix(cKDTree(centroid[ids]), reach + radius[ids].max(),
                                                  output_type="ndarray")
    large = np.flatnonzero(~small)
    point, index = [near["i"]], [ids[near["j"]]]
    for start in range(0, len(points), 256):
        gap = (np.linalg.norm(points[start:start + 256, None] - centroid[large][None], axis=2)
               - radius[large][None])
        where = np.nonzero(gap <= reach)
        point.append(start + where[0])
        index.append(large[where[1]])
    return np.concatenate(point).astype(np.int64), np.concatenate(index).astype(np.int64)


def _lowest_in_ball(p: np.ndarray, n: np.ndarray, tri: np.ndarray, plane: np.ndarray,
                    reach: float) -> tuple[np.ndarray, np.ndarray]:
    """For each pair (point p, unit direction n, triangle tri (3, 3) with unit normal ``plane``):
    the largest (p - q) . n over the triangle's points q within ``reach`` of p, and whether any
    lies within it."""
    best = np.full(len(p), -np.inf)
    r2 = reach * reach

    def offer(q: np.ndarray, where: np.ndarray) -> None:
        np.copyto(best, np.maximum(best, np.einsum("ij,ij->i", p - q, n)), where=where)

    for k in range(3):
        d = tri[:, k] - p
        offer(tri[:, k], np.einsum("ij,ij->i", d, d) <= r2)
    for k in range(3):
        a, e = tri[:, k], tri[:, (k + 1) % 3] - tri[:, k]
        f = a - p
        qa = np.einsum("ij,ij->i", e, e)
        qb = 2.0 * np.einsum("ij,ij->i", e, f)
        qc = np.einsum("ij,ij->i", f, f) - r2
        disc = qb * qb - 4.0 * qa * qc
        real = disc >= 0.0
        root = np.sqrt(np.where(real, disc, 0.0))
        for s in ((-qb - root) / (2.0 * qa), (-qb + root) / (2.0 * qa)):
            offer(a + s[:, None] * e, real & (s >= 0.0) & (s <= 1.0))
    height = np.einsum("ij,ij->i", p - tri[:, 0], plane)
    circle2 = r2 - height * height
    down = -(n - np.einsum("ij,ij->i", n, plane)[:, None] * plane)
    length = np.linalg.norm(down, axis=1)
    q = (p - height[:, None] * plane
         + np.sqrt(np.maximum(circle2, 0.0))[:, None] * down / np.maximum(length, 1e-30)[:, None])
    offer(q, (circle2 > 0.0) & (length > 1e-12) & _inside(q, tri))
    return best, np.isfinite(best)


def _inside(q: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Whether each point q (in its triangle's plane) lies in its triangle."""
    u, v, w = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0], q - tri[:, 0]
    uu, uv, vv = (np.einsum("ij,ij->i", u, u), np.einsum("ij,ij->i", u, v), np.einsum("ij,ij->i", v, v))
    wu, wv = np.einsum("ij,ij->i", w, u), np.einsum("ij,ij->i", w, v)
    den = uu * vv - uv * uv
    s = (vv * wu - uv * wv) / den
    t = (uu * wv - uv * wu) / den
    return (s >= 0.0) & (t >= 0.0) & (s + t <= 1.0)
