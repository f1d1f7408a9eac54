"""The fabric library and fabric files: sources, units, and clear errors."""

import json

import pytest

from party import units
from party.errors import InvalidInput
from party.fabric import fabric_by_name, library, load_fabric


def test_library_has_the_fabrics_users_ask_for_with_sources():
    fabrics = library()
    assert {"wool_flannel", "cotton", "denim", "silk", "knit_jersey"} <= set(fabrics)
    for fabric in fabrics.values():
        assert fabric.source, f"{fabric.name} names no source"
    assert fabrics["denim"].tensile_warp > 10 * fabrics["knit_jersey"].tensile_warp
    assert fabrics["denim"].bending_rigidity > 5 * fabrics["silk"].bending_rigidity


def test_kes_units_convert_once_in_party_units():
    assert units.bending_rigidity_from_kes(1.0) == pytest.approx(9.80665e-5)        # gf cm^2/cm -> N m
    assert units.shear_stiffness_from_kes(1.0) == pytest.approx(56.1879, rel=1e-5)  # gf/cm/deg -> N/m/rad
    assert units.tensile_stiffness_from_kes(5.0) == pytest.approx(9806.65)           # 500 gf/cm at 5 %
    assert units.areal_density_from_mg_per_cm2(23.0) == pytest.approx(0.23)
    assert library()["denim"].bending_rigidity == pytest.approx(0.172 * 9.80665e-5)


def test_toml_and_json_files_give_the_same_fabric(tmp_path):
    values = {"areal_density": 0.2, "tensile_warp": 500.0, "tensile_weft": 400.0, "damping": 30.0,
              "bending_rigidity_kes": 0.05, "shear": 20.0, "friction": 0.4}
    (tmp_path / "mine.json").write_text(json.dumps(values))
    (tmp_path / "mine.toml").write_text("\n".join(f"{k} = {v}" for k, v in values.items()))
    a, b = load_fabric(tmp_path / "mine.json"), fabric_by_name(str(tmp_path / "mine.toml"))
    assert a == b
    assert a.name == "mine" and a.bending_rigidity == pytest.approx(0.05 * 9.80665e-5) and a.friction == 0.4


@pytest.mark.parametrize("content,message", [
    ("areal_density = 0.2\ntensile_warp = 1.0\ntensile_weft = 1.0\ndamping = 1.0\nstiffness = 3",
     "bad.toml: fabric 'bad' has unknown key 'stiffness'"),
    ("areal_density = 0.2\ntensile_warp = 1.0\ndamping = 1.0", "bad.toml: fabric 'bad' lacks tensile_weft"),
    ("areal_density = 0.2\ntensile_warp = 1.0\ntensile_weft = 1.0\ndamping = 1.0\nshear = 5.0\nshear_kes = 1.0",
     "bad.toml: fabric 'bad' gives shear twice (SI and KES)"),
    ("areal_density = 'heavy'", "bad.toml: fabric 'bad': areal_density must be a number, got 'heavy'"),
    ("areal_density = -0.2\ntensile_warp = 1.0\ntensile_weft = 1.0\ndamping = 1.0",
     "bad.toml: fabric 'bad': areal_density = -0.2 kg/m^2 is outside 0.005-3 kg/m^2, the range of real cloth"),
    ("areal_density = [", "fabric file bad.toml is not valid TOML"),
])
def test_bad_fabric_files(tmp_path, content, message):
    path = tmp_path / "bad.toml"
    path.write_text(content)
    with pytest.raises(InvalidInput) as caught:
        fabric_by_name(str(path))
    assert str(caught.value).startswith(message)
    assert "\n" not in str(caught.value)


def test_unknown_fabric_names_the_known_ones():
    with pytest.raises(InvalidInput, match="unknown fabric 'tweed'; known: cotton, denim, knit_jersey, silk, "
                                           "wool_flannel, or a .toml/.json file"):
        fabric_by_name("tweed")
    with pytest.raises(InvalidInput, match="fabric file not found: nowhere.toml"):
        fabric_by_name("nowhere.toml")
