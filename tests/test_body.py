"""The ellipse dress form and body import."""

from pathlib import Path

import numpy as np
import pytest

from party.body import SIZES, dress_form, load_body
from party.body.dress_form import ellipse_semi_axes

GARMENTCODE = Path(__file__).resolve().parents[2] / "shared" / "data" / "garmentcode"


@pytest.mark.parametrize("size", sorted(SIZES))
def test_dress_form_girths_match_measurements(size):
    m = SIZES[size]
    form = dress_form(size).colliders[0]
    v = form.vertices
    for level, girth in ((0.50, m.hip), (0.62, m.waist), (0.72, m.bust)):
        z = level * m.height
        ring = v[np.argsort(np.abs(v[:, 2] - z))[:64]]
        ring = ring[np.argsort(np.arctan2(ring[:, 1] - ring[:, 1].mean(), ring[:, 0]))]
        perimeter = np.linalg.norm(np.diff(np.vstack([ring, ring[:1]])[:, :2], axis=0), axis=1).sum()
        assert perimeter == pytest.approx(girth, rel=0.03)
    assert form.signed_volume() > 0 and form.to_trimesh().is_watertight


def test_ellipse_perimeter_formula_is_exact_for_a_circle():
    a, b = ellipse_semi_axes(1.0, 1.0)
    assert a == pytest.approx(1 / (2 * np.pi)) and b == pytest.approx(a)


@pytest.mark.skipif(not GARMENTCODE.exists(), reason="../shared/data/garmentcode is not present")
def test_mean_all_is_read_y_up_in_metres():
    body = load_body(GARMENTCODE / "bodies" / "mean_all.obj")
    v = body.vertices()
    assert np.ptp(v[:, 2]) == pytest.approx(1.72, abs=0.01)
    assert np.allclose(body.to_file_frame(v)[:, 1], (body.colliders[0].vertices @ body.to_source.T)[:, 1])
    assert abs(body.landmarks["waist"] - 1.07) < 0.05
