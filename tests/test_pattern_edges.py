"""Edge geometry against analytic values."""

import numpy as np
import pytest

from party.pattern import arc_through_radius, bezier, line


def quadratic_length(p0, p1, p2):
    """Closed-form arc length of a quadratic Bezier."""
    a = p0 - 2 * p1 + p2
    b = 2 * (p1 - p0)
    A, B, C = 4 * a @ a, 4 * a @ b, b @ b
    s_abc, a2, c2 = 2 * np.sqrt(A + B + C), np.sqrt(A), 2 * np.sqrt(C)
    a32, ba = 2 * A * a2, B / a2
    return (a32 * s_abc + a2 * B * (s_abc - c2) + (4 * C * A - B * B) * np.log((2 * a2 + ba + s_abc) / (ba + c2))) / (4 * a32)

def test_arc_length_is_radius_times_angle():
    r = 0.3
    for large, expected in ((False, r * np.pi / 2), (True, r * 3 * np.pi / 2)):
        e = arc_through_radius([r, 0.0], [0.0, r], r, large_arc=large, ccw=not large)
        assert e.length() == pytest.approx(expected, rel=1e-12)


def test_arc_points_stay_on_circle_and_split_keeps_length():
    e = arc_through_radius([0.1, 0.0], [-0.1, 0.0], 0.15, large_arc=False, ccw=True)
    pts = e.sample(20)
    assert np.allclose(np.linalg.norm(pts - e.center, axis=1), 0.15, atol=1e-12)
    a, b = e.split(0.3)
    assert a.length() + b.length() == pytest.approx(e.length(), rel=1e-10)
    assert a.length() == pytest.approx(0.3 * e.length(), rel=1e-9)


def test_quadratic_bezier_length_matches_closed_form():
    p0, p1, p2 = np.array([0.0, 0.0]), np.array([0.2, 0.3]), np.array([0.5, 0.05])
    assert bezier(p0, [p1], p2).length() == pytest.approx(quadratic_length(p0, p1, p2), rel=1e-9)


def test_cubic_bezier_equal_to_a_quadratic_has_its_length():
    p0, p1, p2 = np.array([0.0, 0.0]), np.array([0.1, 0.4]), np.array([0.6, 0.1])
    c1, c2 = p0 + 2 / 3 * (p1 - p0), p2 + 2 / 3 * (p1 - p2)  # degree elevation
    assert bezier(p0, [c1, c2], p2).length() == pytest.approx(quadratic_length(p0, p1, p2), rel=1e-9)


def test_samples_are_evenly_spaced_by_arc_length():
    e = bezier([0, 0], [[0.1, 0.5], [0.4, -0.2]], [0.5, 0.1])
    pts = e.sample(200)
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert steps.std() / steps.mean() < 1e-3
    assert steps.sum() == pytest.approx(e.length(), rel=1e-4)


def test_bezier_split_halves_meet_and_add_up():
    e = bezier([0, 0], [[0.2, 0.4]], [0.5, 0.0])
    a, b = e.split(0.5)
    assert np.allclose(a.end, b.start)
    assert a.length() == pytest.approx(b.length(), rel=1e-6)
    assert line([0, 0], [0.3, 0.4]).length() == pytest.approx(0.5)
