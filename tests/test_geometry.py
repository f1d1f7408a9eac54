"""Geometric primitives of the collision package against brute force."""

import numpy as np
import warp as wp

from party.collision.geometry import segment_triangle_distance, step_near, step_within


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


@wp.kernel
def _steps_kept(steps: wp.array(dtype=wp.vec3, ndim=2), margin: float, near: wp.array(dtype=int),
                within: wp.array(dtype=int)):
    k = wp.tid()
    near[k] = int(step_near(steps[k, 0], steps[k, 1], steps[k, 2], steps[k, 3], margin))
    within[k] = int(step_within(steps[k, 0], steps[k, 1], steps[k, 2], steps[k, 3], margin))


def _point_segment_distance(p: np.ndarray, a: np.ndarray, step: np.ndarray) -> np.ndarray:
    t = np.clip(((p - a) * step).sum(-1) / np.maximum((step * step).sum(-1), 1e-30), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[..., None] * step), axis=-1)


def test_a_step_near_the_searched_step_stays_within_the_reach_its_candidates_were_kept_by():
    """step_near: every point of an accepted step lies within the margin of the searched step's
    segment, hence within its length plus the margin of where it was searched from (the bound
    keep_candidate keeps triangles by); the box test reaches sqrt(3) times the margin."""
    rng = np.random.default_rng(5)
    margin = 2.0e-3
    n = 4000
    ref = rng.uniform(-0.01, 0.01, (n, 3))
    ref_step = rng.normal(0.0, 2.0e-3, (n, 3))
    ref_step[:500] = 0.0  # a node searched at rest
    start = ref + rng.uniform(0.0, 1.0, (n, 1)) * ref_step + rng.normal(0.0, 1.2e-3, (n, 3))
    end = start + ref_step + rng.normal(0.0, 1.2e-3, (n, 3))
    corner = np.array([ref[0] + margin, ref[0] + margin])  # a step at the box's corner
    steps = np.stack([start, end, ref, ref_step], axis=1)
    steps[0] = [corner[0], corner[1], ref[0], np.zeros(3)]
    near, within = wp.zeros(n, dtype=int, device="cpu"), wp.zeros(n, dtype=int, device="cpu")
    wp.launch(_steps_kept, dim=n, inputs=[wp.array(steps.astype(np.float32), dtype=wp.vec3, device="cpu"), margin,
                                          near, within], device="cpu")
    near, within = near.numpy().astype(bool), within.numpy().astype(bool)
    s = np.linspace(0.0, 1.0, 50)[:, None, None]
    on_step = steps[None, :, 0] + s * (steps[None, :, 1] - steps[None, :, 0])
    farthest = _point_segment_distance(on_step, steps[None, :, 2], steps[None, :, 3]).max(axis=0)
    assert np.all(farthest[near] <= margin * (1.0 + 1e-4))
    assert np.all(farthest[~near] > margin * (1.0 - 1e-4))
    reach = np.linalg.norm(on_step - steps[None, :, 2], axis=-1).max(axis=0)
    assert np.all(reach[near] <= np.linalg.norm(steps[near, 3], axis=-1) + margin * (1.0 + 1e-4))
    assert 0.2 < near.mean() < 0.8
    assert within[0] and not near[0] and np.isclose(reach[0], np.sqrt(3.0) * margin)


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
