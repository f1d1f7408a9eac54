"""Malformed patterns and bodies: each gets a one-line error naming what is at fault, and the
CLI exits non-zero without writing an output folder."""

import copy
import json
import subprocess
import sys

import numpy as np
import pytest
import trimesh

from party.body import load_body
from party.errors import InvalidInput
from party.pattern import load_pattern

SQUARE = {"vertices": [[0, 0], [40, 0], [40, 50], [0, 50]],
          "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2], "name": "side"}, {"endpoints": [2, 3]},
                    {"endpoints": [3, 0]}], "grain": [0, 1]}
GOOD = {"format": "party-pattern", "version": 1, "units": "cm",
        "panels": {"front": copy.deepcopy(SQUARE), "back": copy.deepcopy(SQUARE)},
        "seams": [{"a": {"panel": "front", "edge": 1}, "b": {"panel": "back", "edge": 3}}]}


def write(tmp_path, doc, name="p.json"):
    path = tmp_path / name
    path.write_text(json.dumps(doc) if not isinstance(doc, str) else doc)
    return path


def broken(change):
    doc = copy.deepcopy(GOOD)
    change(doc)
    return doc


def set_(path, value):
    def change(doc):
        target = doc
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value
    return change


PATTERN_CASES = {
    "unknown panel in seam": (set_(["seams", 0, "a", "panel"], "sleeve"), "unknown panel 'sleeve'"),
    "unknown edge index": (set_(["seams", 0, "b", "edge"], 9), "panel 'back' has no edge 9"),
    "unknown edge name": (set_(["seams", 0, "b", "edge"], "hem"), "panel 'back' has no edge named 'hem'"),
    "edge sewn twice": (lambda d: d["seams"].append({"a": {"panel": "front", "edge": 1}, "b": {"panel": "back", "edge": 1}}),
                        "front.edge[1] is already sewn"),
    "edge sewn to itself": (set_(["seams", 0, "b"], {"panel": "front", "edge": 1}),
                            "seam front.edge[1] - front.edge[1] joins an edge to itself"),
    "seam lengths beyond any gather": (set_(["panels", "back", "vertices"], [[0, 0], [40, 0], [40, 250], [0, 250]]),
                                       "edge lengths 50.0 cm and 250.0 cm would gather 5.0 to 1, beyond the 4 to 1 a "
                                       "garment gathers"),
    "open outline": (set_(["panels", "front", "edges"], [{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}]),
                     "outline is open between edge 2 and edge 0"),
    "self-intersecting outline": (set_(["panels", "front", "vertices"], [[0, 0], [40, 50], [40, 0], [0, 50]]),
                                  "outline crosses itself"),
    "zero-area panel": (set_(["panels", "front", "vertices"], [[0, 0], [40, 0], [80, 0], [120, 0]]),
                        "panel 'front': outline encloses no area"),
    "missing grain": (lambda d: d["panels"]["front"].pop("grain"), "'grain' is a required property"),
    "zero grain": (set_(["panels", "front", "grain"], [0, 0]), "missing or invalid grain line"),
    "bezier with NaN": (set_(["panels", "front", "edges", 0, "curve"], {"type": "quadratic", "control": [[float("nan"), 3]]}),
                        "non-finite coordinate"),
    "unit mismatch": (set_(["units"], "m"), "the file's units do not match its numbers"),
    "unknown unit": (set_(["units"], "furlong"), "invalid pattern at units"),
    "vertex out of range": (set_(["panels", "front", "edges", 0, "endpoints"], [0, 7]), "edge 0 names vertex 7"),
    "arc too tight": (set_(["panels", "front", "edges", 2, "curve"], {"type": "arc", "radius": -5}), "invalid pattern at panels/front/edges/2/curve"),
    "overlapping seam ranges": (lambda d: d["seams"].append({"a": {"panel": "front", "edge": 3, "range": [0.0, 0.6]},
                                                              "b": {"panel": "back", "edge": 1, "range": [0.0, 0.6]}})
                                or d["seams"].append({"a": {"panel": "front", "edge": 3, "range": [0.5, 1.0]},
                                                      "b": {"panel": "back", "edge": 1, "range": [0.5, 1.0]}}),
                                "overlap"),
    "no panels": (set_(["panels"], {}), "invalid pattern at panels"),
}


@pytest.mark.parametrize("case", sorted(PATTERN_CASES))
def test_malformed_pattern_gets_a_one_line_error(tmp_path, case):
    change, message = PATTERN_CASES[case]
    path = write(tmp_path, broken(change))
    with pytest.raises(InvalidInput) as info:
        load_pattern(path)
    assert message in str(info.value)
    assert "\n" not in str(info.value)


def test_the_good_pattern_loads(tmp_path):
    pattern = load_pattern(write(tmp_path, GOOD))
    assert pattern.edge(pattern.seams[0].a).length() == pytest.approx(0.5)


def test_seam_range_sews_part_of_an_edge(tmp_path):
    doc = broken(lambda d: d["seams"].append({"a": {"panel": "front", "edge": 3, "range": [0.0, 0.5]},
                                              "b": {"panel": "back", "edge": 1, "range": [0.5, 1.0]}}))
    pattern = load_pattern(write(tmp_path, doc))
    assert len(pattern.panels["front"].edges) == 5
    assert pattern.edge(pattern.seams[1].a).length() == pytest.approx(0.25)


@pytest.mark.parametrize("content, suffix, message", [
    ("{not json", ".json", "not valid JSON"),
    ('{"hello": 1}', ".json", "not a pattern"),
    ("panels", ".txt", "unknown pattern format .txt"),
    ('{"pattern": {"panels": {}}, "properties": {}}', ".json", "units_in_meter must be a positive number"),
])
def test_wrong_pattern_files(tmp_path, content, suffix, message):
    path = write(tmp_path, content, "p" + suffix)
    with pytest.raises(InvalidInput, match=message):
        load_pattern(path)


def test_garmentcode_unknown_curvature(tmp_path):
    doc = {"properties": {"units_in_meter": 100}, "pattern": {"panels": {"a": {
        "vertices": [[0, 0], [30, 0], [30, 30]], "translation": [0, 0, 0], "rotation": [0, 0, 0],
        "edges": [{"endpoints": [0, 1], "curvature": {"type": "spline", "params": []}}, {"endpoints": [1, 2]},
                  {"endpoints": [2, 0]}]}}, "stitches": []}}
    with pytest.raises(InvalidInput, match="panel 'a' edge 0: unknown curvature type 'spline'"):
        load_pattern(write(tmp_path, doc))


def test_pattern_file_not_found(tmp_path):
    with pytest.raises(InvalidInput, match="pattern file not found"):
        load_pattern(tmp_path / "missing.json")


def box_file(tmp_path, mesh, name="body.obj"):
    path = tmp_path / name
    mesh.export(path)
    return path


@pytest.mark.parametrize("make, message", [
    (lambda: trimesh.creation.box([0.3, 0.2, 1.7]).invert() or None, "inward-facing normals"),
    (lambda: trimesh.Trimesh(trimesh.creation.box([0.3, 0.2, 1.7]).vertices, trimesh.creation.box([0.3, 0.2, 1.7]).faces[:-2]),
     "not closed"),
    (lambda: trimesh.creation.box([0.3, 0.2, 17.0]), "cannot tell the units of a body 17 units tall"),
])
def test_bad_body_meshes(tmp_path, make, message):
    mesh = make()
    if mesh is None:
        mesh = trimesh.creation.box([0.3, 0.2, 1.7])
        mesh.invert()
    with pytest.raises(InvalidInput, match=message):
        load_body(box_file(tmp_path, mesh))


def test_empty_body_mesh(tmp_path):
    path = tmp_path / "empty.obj"
    path.write_text("# nothing\n")
    with pytest.raises(InvalidInput, match="empty.obj"):
        load_body(path)


@pytest.mark.parametrize("spec, message", [("missing.obj", "body file not found"), ("XXL", "body file not found")])
def test_body_not_found(spec, message):
    with pytest.raises(InvalidInput, match=message):
        load_body(spec)


def test_body_wrong_format(tmp_path):
    path = tmp_path / "body.xyz"
    path.write_text("1 2 3\n")
    with pytest.raises(InvalidInput, match="unknown body format .xyz"):
        load_body(path)


def test_body_in_centimetres_is_detected(tmp_path):
    mesh = trimesh.creation.box([30.0, 20.0, 170.0])
    body = load_body(box_file(tmp_path, mesh))
    assert np.ptp(body.vertices()[:, 2]) == pytest.approx(1.7)


def test_cli_exits_non_zero_and_writes_nothing(tmp_path):
    path = write(tmp_path, broken(set_(["seams", 0, "a", "panel"], "sleeve")))
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, "-m", "party.cli", "drape", str(path), "--out", str(out), "--no-progress"],
                         capture_output=True, text=True)
    assert run.returncode == 1
    assert run.stderr.strip().count("\n") == 0 and "unknown panel 'sleeve'" in run.stderr
    assert not out.exists()
