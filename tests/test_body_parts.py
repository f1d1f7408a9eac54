"""GarmentCode's collision filter by body part: a skirt's cloth passes through the arms and rests
on the rest of the body; the parts come from the segmentation beside GarmentCode's bodies."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import trimesh

from party.body import ColliderMesh, sphere
from party.body.load import load_body
from party.body.probe import ColliderProbe
from party.body.segmentation import ARMS, part_bits, read_segmentation
from party.errors import InvalidInput
from party.garment.assemble import assemble
from party.garment.body_parts import garment_ignored_parts, sewn_ignored_parts
from party.model import ModelBuilder
from party.solvers.registry import solver_class

from conftest import simulate
from test_sewing import tube_pattern

BODIES = Path(__file__).resolve().parents[2] / "shared" / "data" / "garmentcode" / "bodies"
needs_bodies = pytest.mark.skipif(not BODIES.exists(), reason="../shared/data/garmentcode/bodies is not present")


def arm_ball() -> ColliderMesh:
    """A ball of radius 0.1 m at the origin, every vertex of it in the left arm."""
    ball = sphere(0.1, subdivisions=3)
    return replace(ball, vertex_parts=np.full(len(ball.vertices), part_bits("left_arm"), np.int32))


@pytest.mark.parametrize("solver", ["explicit", "implicit"])
def test_a_node_falls_through_a_part_it_passes_through_and_rests_on_it_otherwise(solver):
    builder = ModelBuilder()
    through = builder.add_node((0.01, 0.0, 0.15), 1e-3)
    resting = builder.add_node((-0.01, 0.0, 0.15), 1e-3)
    builder.ignore_body_parts([through], ARMS)
    builder.add_collider(arm_ball())
    model = builder.finalize("cpu")
    dt = solver_class(solver).default_dt
    z = simulate(model, solver_class(solver)(model), round(0.4 / dt), dt).positions()[:, 2]  # a free fall of 0.78 m
    assert z[through] < -0.5
    assert 0.09 < z[resting] < 0.11  # on the ball's top


def test_a_point_inside_a_part_it_passes_through_is_not_counted_inside():
    probe = ColliderProbe([arm_ball()])
    points = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.05], [0.0, 0.0, 0.3]])
    assert probe.inside_and_distance(points)[0].tolist() == [True, True, False]
    inside, _ = probe.inside_and_distance(points, ignored_parts=np.array([ARMS, 0, ARMS]))
    assert inside.tolist() == [False, True, False]


def test_a_seam_node_passes_through_a_part_only_where_every_panel_sewn_into_it_does():
    pattern = tube_pattern()
    pattern = replace(pattern, panels={**pattern.panels, "front": replace(pattern.panels["front"], label="leg")})
    garment = assemble(pattern, 0.02)
    per_node = garment_ignored_parts(garment)
    front, back = (slice(garment.node_offsets[k], garment.node_offsets[k + 1]) for k in range(2))
    assert set(per_node[front]) == {ARMS} and set(per_node[back]) == {0}
    net, node_map = garment.sewn()
    sewn = sewn_ignored_parts(garment, node_map)
    seam = np.unique(node_map[garment.seam_pairs])
    assert set(sewn[seam]) == {0}
    only_front = np.setdiff1d(node_map[front], seam)
    assert len(only_front) > 0 and set(sewn[only_front]) == {ARMS}


@needs_bodies
def test_garmentcode_bodies_carry_their_parts_and_the_faces_where_an_arm_joins_collide():
    body = load_body(BODIES / "mean_female.obj").colliders[0]
    doc = json.loads((BODIES / "ggg_body_segmentation.json").read_text())
    assert np.all(body.vertex_parts[doc["left_arm"]] == part_bits("left_arm"))
    faces = body.face_parts()
    corners = body.vertex_parts[body.faces]
    mixed = (corners[:, 0] != corners[:, 1]) | (corners[:, 1] != corners[:, 2])
    assert mixed.any() and np.all(faces[mixed] == 0)
    assert 0.2 < np.mean(faces & ARMS != 0) < 0.3  # the arms hold about a quarter of the surface


@needs_bodies
def test_a_body_of_another_topology_beside_the_shared_file_has_no_parts_and_its_own_file_must_fit(tmp_path):
    box = trimesh.creation.box((0.4, 0.3, 1.7))
    box.export(tmp_path / "person.obj")
    (tmp_path / "ggg_body_segmentation.json").write_text((BODIES / "ggg_body_segmentation.json").read_text())
    assert read_segmentation(tmp_path / "person.obj", len(box.vertices)) is None
    assert load_body(tmp_path / "person.obj").colliders[0].vertex_parts is None
    (tmp_path / "person_segmentation.json").write_text(json.dumps({"left_arm": [0, 1, 99]}))
    with pytest.raises(InvalidInput, match=r"person_segmentation\.json: its vertex indices do not fit person\.obj "
                                           r"\(8 vertices\)$"):
        load_body(tmp_path / "person.obj")


def test_our_pattern_format_carries_a_panel_label_through_to_the_filter(tmp_path):
    from party.pattern import load_pattern

    doc = json.loads((Path(__file__).resolve().parents[1] / "party" / "data" / "patterns" / "dress_sleeves.json")
                     .read_text())
    doc["panels"]["skirt_front"]["label"] = "leg"
    (tmp_path / "dress.json").write_text(json.dumps(doc))
    garment = assemble(load_pattern(tmp_path / "dress.json"), 0.04)
    names = list(garment.pattern.panels)
    per_node = garment_ignored_parts(garment)
    for k, name in enumerate(names):
        span = per_node[garment.node_offsets[k]:garment.node_offsets[k + 1]]
        assert set(span) == ({ARMS} if name == "skirt_front" else {0})
