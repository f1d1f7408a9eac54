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


SPACING_MM = "30"  # coarse, for CI


def _drape(path: Path, out: Path, images: bool, solver: str = "explicit") -> dict:
    import json
    import subprocess
    import sys

    run = subprocess.run([sys.executable, "-m", "party.cli", "drape", str(path), "--body", str(DATA / "bodies" / "mean_all.obj"),
                          "--spacing-mm", SPACING_MM, "--out", str(out), "--no-progress", "--solver", solver]
                         + ([] if images else ["--no-images"]), capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr
    return json.loads((out / "summary.json").read_text())


@pytest.fixture(scope="module")
def pencil_drape(tmp_path_factory):
    out = tmp_path_factory.mktemp("pencil") / "out"
    return out, _drape(DATA / "patterns" / "dress_pencil_specification.json", out, images=True)


@pytest.mark.parametrize("path", [p for p in SAMPLES if "pencil" not in p.name],
                         ids=lambda p: p.name.removesuffix("_specification.json"))
@pytest.mark.slow
def test_sample_drapes_on_mean_all_closed_and_clean(path, tmp_path):
    from party.garment.sewing import SewingSettings

    summary = _drape(path, tmp_path / "out", images=False)
    _assert_closed_and_clean(summary)
    # each fits mean_all: what sewing left stretched, settling pulled back (the jumpsuit came out
    # of one round of settling with its front bodice at 5.0 times rest over the shoulders)
    assert summary["max_sewn_elongation"] < SewingSettings().overstretched


@pytest.mark.parametrize("name", ["dress_sleeves_flare", "hoody_mean", "dress_pencil", "js_mean_all"])
@pytest.mark.slow
def test_sample_drapes_closed_and_clean_with_the_implicit_solver(name, tmp_path):
    # draping in 1/300 s steps needs the crossing guard (the flare dress: 21 crossings without
    # it), checking every edge (the hoody: 2 crossings when only edges near cloth were checked)
    summary = _drape(DATA / "patterns" / f"{name}_specification.json", tmp_path / "out", images=False,
                     solver="implicit")
    _assert_closed_and_clean(summary)
    assert summary["body_vertices_through_cloth"] == 0  # its triangles are held off the body's vertices too
    if name == "dress_pencil":
        # sewn tighter than mean_all (its waist at 1.5 times rest); before the stretched elements
        # kept their sewn length as their limit, the waist tore to 4.9 times rest and a node
        # ended inside the body. It creeps on for more than the 10 s allowed.
        assert summary["max_sewn_elongation"] > 1.4
    else:
        assert summary["relaxation"]["at_rest"]  # its shape steady to a millimetre, within 10 s


@pytest.mark.slow
def test_pencil_dress_drapes_on_mean_all_closed_and_clean(pencil_drape):
    _, summary = pencil_drape
    _assert_closed_and_clean(summary)
    assert summary["panels"] == 6 and summary["seams"] == 23


def _assert_closed_and_clean(summary: dict) -> None:
    """Issue 3's bar for every sample: seams closed to under 2 mm, no node inside the body and
    no cloth edge through a cloth triangle; and draping stretches no element beyond the
    fabric's limit (wool flannel's 1.0995), or beyond what sewing left where that was more. The
    body's vertices are held off the cloth's triangles too (the body showing through them): at
    most 2 stay through, where a tight garment's limit holds its triangles against the body in
    the explicit drape (the jumpsuit's 2 and the pencil dress's 1; before the explicit drape
    held them off, the samples had 14 to 551)."""
    assert summary["max_seam_gap_mm"] < 2.0
    assert summary["body_penetrations"] == 0
    assert summary["cloth_crossings"] == 0
    assert summary["body_vertices_through_cloth"] <= 2
    assert summary["max_elongation"] <= max(summary["max_sewn_elongation"], 1.0995) * 1.02


def test_drape_outputs_are_in_the_bodys_frame_with_uvs(pencil_drape):
    import trimesh

    out, summary = pencil_drape
    body = trimesh.load(out / "body.obj", process=False)
    source = trimesh.load(DATA / "bodies" / "mean_all.obj", process=False)
    assert np.allclose(body.vertices, source.vertices, atol=1e-5)
    garment = trimesh.load(out / "garment.obj", process=False)
    assert garment.visual.uv.shape == (len(garment.vertices), 2)
    lo, hi = source.bounds
    assert np.all(garment.vertices.min(axis=0) > lo - 0.2) and np.all(garment.vertices.max(axis=0) < hi + 0.2)
    # the skirt hangs down the body's Y axis, below the waist
    assert garment.vertices[:, 1].min() < 0.7
    glb = trimesh.load(out / "garment.glb", force="mesh", process=False)
    assert len(glb.faces) == len(garment.faces)
    for view in ("front", "side", "back"):
        assert (out / "images" / f"{view}.png").exists()


@pytest.mark.parametrize("fabric", ["denim", "silk"])
def test_tshirt_sews_with_no_crossing_in_a_stiff_and_a_light_fabric(fabric):
    """GarmentCode's tshirt at 20 mm was sewn with 15 crossings in denim and 14 in silk, where a
    sleeve panel, free to pass through the others while the seams close, folded through itself
    at the armpit; the joined garment kept them (collision keeps a node on its side of a
    layer), and denim's implicit drape, caught on them, stretched to 1.74 times rest."""
    from party.body.load import load_body
    from party.fabric import library
    from party.output.metrics import cloth_crossings
    from party.garment.sewing import sew

    garment = assemble(load_pattern(DATA / "patterns" / "tshirt_mean_specification.json"), 0.02)
    sewn = sew(garment, load_body(str(DATA / "bodies" / "mean_all.obj")), library()[fabric])
    assert sewn.max_seam_gap < 1.0e-3
    assert cloth_crossings(sewn.points, sewn.net.triangles) == 0


@pytest.mark.slow
def test_the_jumpsuit_in_denim_sews_closed():
    """Denim's explicit steps are 2.3 times shorter than wool flannel's: after the sewing's
    6,000 iterations the jumpsuit's seams were still 227 mm apart and were joined so. Sewing
    goes on while a seam is more than 1 cm open (18,000 iterations here)."""
    from party.body.load import load_body
    from party.fabric import library
    from party.garment.sewing import sew

    garment = assemble(load_pattern(DATA / "patterns" / "js_mean_all_specification.json"), 0.02)
    sewn = sew(garment, load_body(str(DATA / "bodies" / "mean_all.obj")), library()["denim"])
    assert sewn.max_seam_gap < 1.0e-3
    assert sewn.relaxation.iterations > 6000


@pytest.mark.slow
def test_the_tshirt_in_denim_drapes_with_the_explicit_solver_with_no_crossing(tmp_path):
    """The explicit drape relaxes with the crossing guard, and checks what its interval left
    unchecked when the relaxation stops: without the guard the denim tshirt ended with 9
    crossings, with it but without that last check 4."""
    from party.fabric import library
    from party.scenes.drape import DrapeSettings, drape

    summary = drape(DATA / "patterns" / "tshirt_mean_specification.json", str(DATA / "bodies" / "mean_all.obj"),
                    library()["denim"], tmp_path / "out", DrapeSettings(images=False, progress=False))
    _assert_closed_and_clean(summary)


@pytest.mark.slow
def test_the_shirt_in_denim_drapes_with_the_implicit_solver_to_rest_unstretched(tmp_path):
    """Stiff, heavy cloth that the body holds up: the implicit solve keeps each node that was
    against the body on its side (a body plane), so Collision() no longer stops nodes that the
    solve's elastic pull sent centimetres into the body while their neighbours went on.
    Without the planes the denim shirt's armpits stretched to 1.70 times rest and it was not
    at rest after 10 s."""
    from party.fabric import library
    from party.scenes.drape import DrapeSettings, drape

    summary = drape(DATA / "patterns" / "shirt_mean_specification.json", str(DATA / "bodies" / "mean_all.obj"),
                    library()["denim"], tmp_path / "out", DrapeSettings(images=False, progress=False, solver="implicit"))
    _assert_closed_and_clean(summary)
    assert summary["relaxation"]["at_rest"]


def jumpsuit_sewn_stretch(fabric_name: str) -> np.ndarray:
    """GarmentCode's jumpsuit sewn at 20 mm on mean_all in ``fabric_name``: its limited
    elements' lengths over rest."""
    from party.body import load_body
    from party.fabric import fabric_by_name
    from party.garment.sewing import sew
    from party.garment.worn import garment_model

    garment = assemble(load_pattern(DATA / "patterns" / "js_mean_all_specification.json"), 0.02)
    body = load_body(str(DATA / "bodies" / "mean_all.obj"))
    fabric = fabric_by_name(fabric_name)
    sewn = sew(garment, body, fabric, device="cpu")
    model = garment_model(sewn.net, fabric, sewn.points, body, sewn=False)
    nodes, rest = model.elements[model.limited_elements], model.host.element_rest_length[model.limited_elements]
    return np.linalg.norm(sewn.points[nodes[:, 1]] - sewn.points[nodes[:, 0]], axis=1) / rest


@pytest.mark.slow
def test_stiff_cloth_settles_on_while_rounds_help_though_its_energy_has_settled():
    # cotton's small explicit steps met the energy criterion in the jumpsuit's first settling round
    # with 184 elements beyond 1.5 times rest (up to 7.6 at hips and shoulders), which ended the rounds
    from party.garment.sewing import SewingSettings

    assert jumpsuit_sewn_stretch("cotton").max() < SewingSettings().overstretched


@pytest.mark.slow
def test_denim_settles_on_while_its_excess_falls_though_its_worst_elements_stretch_further():
    """The limit gathers a stretched panel's excess into the elements the body holds out: the
    denim jumpsuit's first settling rounds left 140 and 170 elements beyond 1.5 times rest, up to
    5.5 and 6.3, while its total excess fell by a third each round. Stopped once the count did
    not fall, it was sewn at 5.45 with 140 beyond 1.5; going on while the excess falls, at 1.49
    with none after nine rounds."""
    stretch = jumpsuit_sewn_stretch("denim")
    assert (stretch > 1.5).sum() < 10
    assert stretch.max() < 2.5
