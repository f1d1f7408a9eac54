"""Geometric primitives of the collision package against brute force."""

import numpy as np
import warp as wp

from party.collision.geometry import segment_triangle_distance


@wp.kernel
def _distances(segments: wp.array(dtype=wp.vec3, ndim=2), triangles: wp.array(dtype=wp.vec3, ndim=2),
               out: wp.array(dtype=float)):
    k = wp.tid()
    out[k] = segment_triangle_distance(segments[k, 0], segments[k, 1], triangles[k, 0], triangles[k, 1],
                                       triangles[k, 2])


def _sampled_distance(segment: np.ndarray, triangle: np.ndarray, n: int = 120) -> float:
    """Smallest distance between points sampled densely on the segment and on the triangle."""
    s = np.linspace(0.0, 1.0, n)
    on_segment = segment[0] + s[:, None] * (segment[1] - segment[0])
    u, v = np.meshgrid(s, s)
    keep = u + v <= 1.0
    u, v = u[keep], v[keep]
    on_triangle = triangle[0] + u[:, None] * (triangle[1] - triangle[0]) + v[:, None] * (triangle[2] - triangle[0])
    return float(np.sqrt(((on_segment[:, None, :] - on_triangle[None, :, :]) ** 2).sum(-1)).min())


def test_segment_triangle_distance_is_the_smallest_distance_between_their_points():
    rng = np.random.default_rng(3)
    segments = rng.uniform(-1.0, 1.0, (60, 2, 3)).astype(np.float32)
    triangles = rng.uniform(-1.0, 1.0, (60, 3, 3)).astype(np.float32)
    segments[:10] *= 0.1  # short segments, often beside a face
    segments[10:20, 1] = segments[10:20, 0] + 1e-6  # almost a point
    out = wp.zeros(60, dtype=float, device="cpu")
    wp.launch(_distances, dim=60, inputs=[wp.array(segments, dtype=wp.vec3, device="cpu"),
                                          wp.array(triangles, dtype=wp.vec3, device="cpu"), out], device="cpu")
    exact = out.numpy()
    sampled = np.array([_sampled_distance(s.astype(float), t.astype(float)) for s, t in zip(segments, triangles)])
    # sampling finds a distance at least the true one, and within a sample spacing of it
    assert np.all(exact <= sampled + 1e-5)
    assert np.all(sampled - exact < 0.03)
    assert (exact == 0.0).sum() > 0 and (exact > 0.1).sum() > 10


def test_a_points_distance_to_a_surface_is_to_its_nearest_point_not_its_nearest_node():
    """Points over a 1 m square of two triangles (nodes at its corners only): 5 mm over its
    middle lies 5 mm from the surface (0.7 m from any node); beyond an edge, the distance is to
    the edge; beyond a corner, to the corner."""
    from party.output.metrics import distances_to_surface

    square = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    triangles = np.array([[0, 1, 2], [0, 2, 3]])
    points = np.array([[0.5, 0.5, 0.005], [0.5, -0.03, 0.04], [1.03, 1.04, 0.0]])
    expected = [0.005, 0.05, 0.05]
    assert np.allclose(distances_to_surface(points, square, triangles), expected, atol=1e-6)
