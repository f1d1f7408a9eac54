"""DXF-AAMA import, on files written here with ezdxf in the AAMA layout."""

import json

import ezdxf
import numpy as np
import pytest

from party.errors import InvalidInput
from party.garment.assemble import assemble
from party.pattern import load_pattern


def write_piece(doc, name, outline_cm, grain, turns=True):
    block = doc.blocks.new(name=name.upper())
    block.add_polyline2d(outline_cm, close=True, dxfattribs={"layer": "1"})
    if grain is not None:
        block.add_line(grain[0], grain[1], dxfattribs={"layer": "7"})
    if turns:
        for p in outline_cm:
            block.add_point(p, dxfattribs={"layer": "2"})
    block.add_text(f"Piece Name: {name}", dxfattribs={"layer": "1"})
    doc.modelspace().add_blockref(name.upper(), (0, 0))


def aama(tmp_path, grain=True, units=5):
    doc = ezdxf.new("R2000")
    doc.header["$INSUNITS"] = units
    # a curved side as a digitised polyline between turn points
    side = [(40 + 3 * np.sin(np.pi * t), 50 * t) for t in np.linspace(0, 1, 11)]
    front = [(0, 0)] + side + [(0, 50)]
    block = doc.blocks.new(name="FRONT")
    block.add_polyline2d(front, close=True, dxfattribs={"layer": "1"})
    block.add_line((20, 5), (20, 45), dxfattribs={"layer": "7"}) if grain else None
    for p in [(0, 0), (40, 0), (40, 50), (0, 50)]:
        block.add_point(p, dxfattribs={"layer": "2"})
    block.add_text("Piece Name: front", dxfattribs={"layer": "1"})
    doc.modelspace().add_blockref("FRONT", (0, 0))
    write_piece(doc, "back", [(0, 0), (40, 0), (40, 50), (0, 50)], ((20, 5), (20, 45)))
    path = tmp_path / "shirt.dxf"
    doc.saveas(path)
    (tmp_path / "shirt.seams.json").write_text(json.dumps({
        "seams": [{"a": {"panel": "front", "edge": 1}, "b": {"panel": "back", "edge": 3}}],
        "parts": {"front": "front", "back": "back"}}))
    return path


def test_pieces_grain_and_seams_are_read(tmp_path):
    pattern = load_pattern(aama(tmp_path))
    assert set(pattern.panels) == {"front", "back"}
    front = pattern.panels["front"]
    assert len(front.edges) == 4
    assert front.edges[1].kind == "polyline"
    assert np.allclose(front.grain, [0, 1])
    assert front.edges[0].length() == pytest.approx(0.40)
    assert front.edges[1].length() > 0.50
    assert front.part == "front"
    g = assemble(pattern, 0.02)
    a = g.panels[0].edge_nodes[1]
    b = g.panels[1].edge_nodes[3]
    assert len(a) == len(b) == round(front.edges[1].length() / 0.02) + 1


def test_missing_grain_line_is_named(tmp_path):
    with pytest.raises(InvalidInput, match="piece 'front': missing grain line"):
        load_pattern(aama(tmp_path, grain=False))


def test_missing_units_are_asked_for(tmp_path):
    path = aama(tmp_path, units=0)
    with pytest.raises(InvalidInput, match="no length unit"):
        load_pattern(path)
    assert load_pattern(path, units="cm").panels["back"].edges[0].length() == pytest.approx(0.40)
