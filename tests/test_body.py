"""The ellipse dress form and body import."""

import subprocess
import sys
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


def test_crease_normals_are_the_faces_normals_at_convex_sharp_vertices_only():
    """A drum's rim vertex faces up and out: its crease normals are the top's and its side's
    (the side's two faces there, 11.25 degrees apart, count once). A sphere has no creases, and
    the inner corner of an L-shaped block, sharp but concave, gets none either."""
    import trimesh

    from party.body.collider import collider_from_trimesh

    def creases(mesh):
        return collider_from_trimesh(mesh, "prop").crease_normals()

    drum = trimesh.creation.cylinder(radius=0.1, height=0.2, sections=32)
    rim = int(np.flatnonzero((np.abs(drum.vertices[:, 2] - 0.1) < 1e-9) & (drum.vertices[:, 0] > 0.099))[0])
    normals = creases(drum)[rim]
    taken = normals[np.linalg.norm(normals, axis=1) > 0]
    assert len(taken) == 2
    up = np.argmax(taken[:, 2])
    assert np.allclose(taken[up], [0, 0, 1]) and taken[1 - up] @ [1, 0, 0] > np.cos(np.radians(5.7))
    assert not creases(trimesh.creation.icosphere(3)).any()
    outline = np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], float)
    cap = np.array([(0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5)])
    sides = [(i, (i + 1) % 6, (i + 1) % 6 + 6) for i in range(6)] + [(i, (i + 1) % 6 + 6, i + 6) for i in range(6)]
    block = trimesh.Trimesh(np.r_[np.c_[outline, np.zeros(6)], np.c_[outline, np.ones(6)]],
                            np.r_[cap[:, ::-1], cap + 6, sides], process=False)
    inner = np.flatnonzero(np.all(np.abs(block.vertices[:, :2] - (1, 1)) < 1e-9, axis=1))
    outer = np.flatnonzero(np.all(np.abs(block.vertices[:, :2] - (2, 0)) < 1e-9, axis=1))
    assert len(inner) == 2 and not creases(block)[inner].any()
    assert np.all(np.linalg.norm(creases(block)[outer], axis=2).max(axis=1) > 0)


def test_a_probe_made_before_anything_else_starts_warp_quietly():
    """``party run dress``'s first Warp call is a ColliderProbe of the dress form: made before
    party had started Warp, it printed Warp's banner, a missing-CUDA-driver warning and a
    module-load line into the demo's output. One point inside a sphere is counted, and nothing
    else is printed."""
    code = ("import numpy as np; from party.body import sphere; from party.body.probe import ColliderProbe; "
            "print(ColliderProbe([sphere(0.3)]).penetrations(np.zeros((1, 3))))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert (done.returncode, done.stdout, done.stderr) == (0, "1\n", "")
