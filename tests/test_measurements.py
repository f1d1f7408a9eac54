"""GarmentCode's measurements beside a body's mesh: read once with the body, lengths in metres."""

from pathlib import Path

import pytest
import trimesh

from party.body.load import load_body
from party.errors import InvalidInput

BODIES = Path(__file__).resolve().parents[2] / "shared" / "data" / "garmentcode" / "bodies"


@pytest.mark.skipif(not BODIES.exists(), reason="../shared/data/garmentcode/bodies is not present")
def test_garmentcode_measurements_come_in_metres_and_agree_with_the_mesh():
    body = load_body(BODIES / "mean_all.obj")
    m = body.measurements
    assert m["height"] == pytest.approx(1.7199)
    assert m["arm_pose_angle"] == pytest.approx(45.48, abs=0.01)  # an angle, kept in degrees
    # the stature the mesh shows (its floor to its top) is the height the file gives
    assert body.landmarks["top"] - body.vertices()[:, 2].min() == pytest.approx(m["height"], abs=5e-3)
    # GarmentCode's waist level (height - head_l - waist_line) lies at the mesh's narrowest torso
    waist = body.vertices()[:, 2].min() + m["height"] - m["head_l"] - m["waist_line"]
    assert waist == pytest.approx(body.landmarks["waist"], abs=0.03)


def test_a_body_without_a_measurements_file_has_none(tmp_path):
    trimesh.creation.box((0.4, 0.3, 1.7)).export(tmp_path / "person.obj")
    assert load_body(tmp_path / "person.obj").measurements == {}


def test_an_unreadable_measurements_file_is_a_one_line_error(tmp_path):
    trimesh.creation.box((0.4, 0.3, 1.7)).export(tmp_path / "person.obj")
    (tmp_path / "person.yaml").write_text("body: [unclosed\n")
    with pytest.raises(InvalidInput, match=r"person\.yaml: not readable YAML \(\w+\); fix or remove the body's "
                                           r"measurements file$"):
        load_body(tmp_path / "person.obj")
