"""GarmentCode's sample patterns (external data in ../shared/data/garmentcode)."""

from pathlib import Path

import numpy as np
import pytest

from party.garment.assemble import assemble
from party.pattern import load_pattern

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "garmentcode"
SAMPLES = sorted((DATA / "patterns").glob("*_specification.json")) if DATA.exists() else []
pytestmark = pytest.mark.skipif(not DATA.exists(), reason="../shared/data/garmentcode is not present")


def test_all_six_samples_are_there():
    assert len(SAMPLES) == 6


@pytest.mark.parametrize("path", SAMPLES, ids=lambda p: p.name.removesuffix("_specification.json"))
def test_sample_loads_meshes_and_pairs_its_seams(path):
    pattern = load_pattern(path)
    garment = assemble(pattern, 0.03)
    for k, mesh in enumerate(garment.panels):
        area = mesh.net.rest_triangle_areas().sum()
        assert area == pytest.approx(mesh.panel.polygon().area, rel=0.02)
        assert mesh.quality["grain_error_deg"] < 1.0
    for s, seam in enumerate(pattern.seams):
        a = garment.panels[list(pattern.panels).index(seam.a.panel)].edge_nodes[seam.a.edge]
        b = garment.panels[list(pattern.panels).index(seam.b.panel)].edge_nodes[seam.b.edge]
        assert len(a) == len(b)
    # GarmentCode places every panel around its body: front panels in front (z > 0 before our
    # Y-up to Z-up turn, so y < 0 after it)
    fronts = [p for n, p in pattern.panels.items() if "ftorso" in n or "_f" in n[-3:]]
    assert all(p.placement.translation[1] < 0 for p in fronts)
