"""`party validate`: each case at CI resolution meets the tolerances of the issue, and the
references it compares with are right."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from party.fabric import fabric_by_name
from party.validate import (CaseResult, Check, cantilever, catenary, cusick, friction, oscillation, restitution,
                            run_validation)
from party.validate.references import chord_angle, elastic_catenary, heavy_elastica

COTTON = fabric_by_name("cotton")


def assert_passed(result):
    failed = [f"{c.quantity}: {c.simulated} vs {c.reference} (error {c.error}, tolerance {c.tolerance})"
              for c in result.checks if not c.passed]
    assert result.checks and not failed, failed


@pytest.mark.parametrize("gamma,drop", [(0.1, 0.0125), (1, 0.1246), (8, 0.8843), (20, 1.8639), (100, 5.8881)])
def test_heavy_elastica_matches_the_published_tip_drops(gamma, drop):
    tip = heavy_elastica(gamma)[-1]
    assert -tip[1] / tip[0] == pytest.approx(drop, abs=2e-4)


def test_chord_reaches_41_5_degrees_at_gamma_8():
    assert chord_angle(heavy_elastica(8.0)) == pytest.approx(41.5, abs=0.05)


def test_stiff_elastic_catenary_is_the_cosh_catenary():
    from scipy.optimize import brentq

    curve = elastic_catenary(1.0, 0.8, 1.0, 1e9)
    a = brentq(lambda a: 2 * a * np.sinh(0.4 / a) - 1.0, 0.01, 10.0)
    x = curve[:, 0]
    assert np.allclose(curve[:, 1], a * (np.cosh((x - 0.4) / a) - np.cosh(0.4 / a)), atol=1e-7)


def test_oscillation_periods_within_1_percent(solver_name):
    assert_passed(oscillation.run_case(COTTON, solver_name, quick=True))


@pytest.mark.parametrize("spacing", [0.02, 0.01])
def test_implicit_strip_period_within_a_fifth_of_case_1s_tolerance(spacing):
    """The strip's first period with the implicit solver at the quick and the default spacing
    (steps of 1/200 of the period, 10 sweeps): within 0.2 %. With Chebyshev's rho at 0.9
    whatever the coupling it came out 0.44 % and 1.2 % long."""
    period, reference = oscillation.strip_period(COTTON, "implicit", spacing=spacing)
    assert abs(period / reference - 1.0) < 0.002


def test_catenary_within_1_percent_of_span(solver_name):
    assert_passed(catenary.run_case(COTTON, solver_name, quick=True))


def test_friction_cone_decides_and_slides_at_g_sin_minus_mu_cos(solver_name):
    assert_passed(friction.run_case(COTTON, solver_name, quick=True))


def test_restitution_within_1_percent(solver_name):
    assert_passed(restitution.run_case(COTTON, solver_name, quick=True))


@pytest.mark.slow
def test_cantilever_bending_length_within_3_percent(tmp_path, solver_name):
    result = cantilever.run_case(COTTON, solver_name, quick=True, out=tmp_path)
    assert_passed(result)
    assert (tmp_path / "cantilever.png").stat().st_size > 10_000


def test_cantilever_needs_a_bending_rigidity():
    result = cantilever.run_case(fabric_by_name("wool_flannel"), "explicit", quick=True)
    assert result.checks == [] and result.details["skipped"] == "fabric 'wool_flannel' has no bending rigidity"


@pytest.mark.slow
def test_cusick_longer_bending_length_drapes_less():
    """Cotton's bending length (B / W)^(1/3) is 18.8 mm, knit jersey's 13.0 mm: cotton stands
    out further (higher DC). Both lie between hanging straight (DC 0) and not draping at all
    (DC 1), in folds."""
    spacing = cusick.SPACINGS["quick"]
    cotton = cusick.drape_test(COTTON, "explicit", spacing)
    jersey = cusick.drape_test(fabric_by_name("knit_jersey"), "explicit", spacing)
    assert 0.0 < jersey.coefficient < cotton.coefficient - 0.1 < 0.9
    assert cotton.nodes >= 3 and jersey.nodes >= 3


def test_cusick_leaves_out_a_fabric_without_bending_and_says_so():
    result = cusick.run_case(fabric_by_name("wool_flannel"), "explicit", quick=True)
    assert result.checks == []
    assert result.details["skipped"] == "no bending rigidity, no drape to measure: wool_flannel"


def test_fold_count_of_a_known_outline():
    angle = np.linspace(-math.pi, math.pi, 400, endpoint=False)
    outline = np.stack([angle, 0.12 + 0.02 * np.cos(6 * angle)], axis=1)
    assert cusick.count_folds(outline) == 6


def party(*args):
    return subprocess.run([sys.executable, "-m", "party.cli", *args], capture_output=True, text=True, timeout=900)


def test_validate_command_writes_results_and_exits_zero_when_all_pass(tmp_path):
    run = party("validate", "--case", "restitution", "--quick", "--out", str(tmp_path))
    assert run.returncode == 0, run.stderr
    results = json.loads((tmp_path / "results.json").read_text())
    assert results["passed"] is True
    assert [c["case"] for c in results["cases"]] == ["restitution"]
    assert all(c["passed"] for c in results["cases"][0]["checks"])


def test_validate_command_exits_non_zero_when_a_case_misses(tmp_path):
    """A soft fabric whose plastic limit (1 %) stops it stretching as far as the elastic
    catenary of its tensile stiffness says: the strip misses the reference, the command says
    FAIL and exits 1, and results.json records it."""
    fabric = tmp_path / "limited.toml"
    fabric.write_text("areal_density = 0.2\ntensile_warp = 5\ntensile_weft = 5\ndamping = 1\n"
                      "strain_limit = 0.01\n")
    run = party("validate", "--case", "catenary", "--quick", "--fabric", str(fabric), "--out", str(tmp_path / "out"))
    assert run.returncode == 1, run.stdout + run.stderr
    assert "FAIL" in run.stdout
    results = json.loads((tmp_path / "out" / "results.json").read_text())
    checks = results["cases"][0]["checks"]
    assert results["passed"] is False and checks[0]["passed"] and not checks[1]["passed"]


def test_validate_resumed_keeps_the_cases_of_the_same_settings(tmp_path):
    """With --resume the cases results.json holds for the same fabric, solver and resolution are
    kept as they were (a time no run gives shows it), and a run with other settings keeps none."""
    first = party("validate", "--case", "restitution", "--quick", "--out", str(tmp_path))
    assert first.returncode == 0, first.stderr
    results = json.loads((tmp_path / "results.json").read_text())
    assert results["complete"] is True
    results["cases"][0]["wall_seconds"] = 12345.0
    (tmp_path / "results.json").write_text(json.dumps(results))

    kept = party("validate", "--case", "restitution", "--quick", "--out", str(tmp_path), "--resume")
    assert kept.returncode == 0, kept.stderr
    assert json.loads((tmp_path / "results.json").read_text())["cases"] == results["cases"]

    other = party("validate", "--case", "restitution", "--quick", "--solver", "implicit", "--out", str(tmp_path),
                  "--resume")
    assert other.returncode == 0, other.stderr
    assert json.loads((tmp_path / "results.json").read_text())["cases"][0]["wall_seconds"] < 12345.0


def test_validation_runs_the_cases_not_kept_and_reports_after_each(tmp_path):
    """A case kept from an earlier run is taken as it is; the others run, and ``on_result``
    hears of the results so far after each case run (results.json is written there)."""
    kept = CaseResult("restitution", [Check.report("restitution", "kept", 1.0)])
    reports = []
    results = run_validation(["restitution", "friction"], None, "explicit", tmp_path, quick=True,
                             kept={"restitution": kept}, on_result=lambda done: reports.append([r.name for r in done]))
    assert results[0] is kept and results[1].name == "friction" and results[1].checks
    assert reports == [["restitution", "friction"]]


def test_validate_unknown_case_is_one_line_error(tmp_path):
    run = party("validate", "--case", "drop", "--out", str(tmp_path))
    assert run.returncode == 1
    assert run.stderr.strip() == ("error: unknown validation case 'drop'; known: oscillation, catenary, cantilever, "
                                  "friction, restitution, cusick, cusick-measured, convergence")


def test_catenary_deviation_shrinks_with_the_spacing():
    """Case 8's first part: each halving of the spacing brings the strip closer to the elastic
    catenary."""
    deviations = [catenary.strip_deviation(COTTON, "explicit", spacing) for spacing in (0.04, 0.02, 0.01)]
    assert deviations[0] > deviations[1] > deviations[2]


def test_cusick_specimens_are_laid_flat_on_the_pedestal_and_wavy_beyond_it():
    """The waviness is zero on the pedestal, about WAVINESS (rms) at the edge, the same field at
    every mesh resolution, and different for each specimen (seed)."""
    meter = cusick.MATSUDAIRA
    angle = np.linspace(-math.pi, math.pi, 720, endpoint=False)
    edge = meter.specimen_radius * np.c_[np.cos(angle), np.sin(angle)]
    inner = 0.99 * meter.pedestal_radius * np.c_[np.cos(angle), np.sin(angle)]
    rms = [np.sqrt(np.mean(cusick.waviness(edge, meter, seed) ** 2)) for seed in range(8)]
    assert np.all(cusick.waviness(inner, meter, 0) == 0.0)
    assert 0.6 * cusick.WAVINESS < np.sqrt(np.mean(np.square(rms))) < 1.4 * cusick.WAVINESS
    assert not np.allclose(cusick.waviness(edge, meter, 0), cusick.waviness(edge, meter, 1))


def test_report_table_keeps_units_in_brackets():
    """Quantities name their units in brackets, which rich would take for markup and drop."""
    import io

    from rich.console import Console

    from party.validate.checks import CaseResult, Check
    from party.validate.report import print_table

    result = CaseResult("convergence")
    result.checks.append(Check.report("convergence", "cotton cantilever bending length [mm]: observed order", 0.98))
    text = io.StringIO()
    print_table([result], Console(file=text, width=160))
    assert "bending length [mm]: observed order" in text.getvalue()


def test_report_table_says_whether_a_decision_was_right():
    """A yes/no check's error reads "right" or "wrong" (it read "0 (wrong decision)" when right)."""
    import io

    from rich.console import Console

    from party.validate.checks import CaseResult, Check
    from party.validate.report import print_table

    result = CaseResult("friction")
    result.checks.append(Check.decision("friction", "stays at 28.96 deg", True, True))
    result.checks.append(Check.decision("friction", "slides at 32.96 deg", False, True))
    text = io.StringIO()
    print_table([result], Console(file=text, width=160))
    rows = [line for line in text.getvalue().splitlines() if "deg" in line]
    assert "right" in rows[0] and "pass" in rows[0] and "wrong" not in rows[0]
    assert "wrong" in rows[1] and "FAIL" in rows[1]


MEASURED = pytest.mark.skipif(not cusick.MEASURED.exists(),
                              reason=f"measured fabric data not found at {cusick.MEASURED}")


def measured_specimens(name: str, solver: str):
    """Case 7's specimens of measured fabric ``name`` draped by ``solver`` (three, as the case
    drapes them), with its measured DC [%] and folds."""
    fabric, dc, nodes = next(row for row in cusick.measured_fabrics() if row[0].name == name)
    drapes = cusick.drape_specimens(fabric, solver, cusick.MEASURED_SPACING, cusick.MATSUDAIRA,
                                    cusick.SPECIMENS["default"])
    return drapes, dc, nodes


@pytest.fixture(scope="module")
def measured_drapes():
    """Case 7's specimens, each draped once per module: ``get(name, solver)``."""
    drapes = {}

    def get(name: str, solver: str):
        if (name, solver) not in drapes:
            drapes[name, solver] = measured_specimens(name, solver)
        return drapes[name, solver]

    return get


@MEASURED
@pytest.mark.slow
def test_both_solvers_drape_a_measured_cusick_specimen_alike(measured_drapes):
    """Measured fabric B (wool tropical, with its bending hysteresis) on Matsudaira's
    drapemeter at 7.5 mm, first specimen: the implicit solver's DC within 3 points of the
    explicit solver's. Its body-vertex response once pushed the cloth on the pedestal's rim
    outward along the rim's vertex normals, and the specimen drooped to 32.8 % against 42.3 %;
    at its own step of 1/300 s it drapes to 39.9 % (three specimens; see cusick.FALL_STEP)."""
    explicit = measured_drapes("measured_B", "explicit")[0][0]
    implicit = measured_drapes("measured_B", "implicit")[0][0]
    assert abs(implicit.coefficient - explicit.coefficient) < 0.03


@MEASURED
@pytest.mark.slow
def test_measured_fabrics_drape_within_case_7s_tolerance(measured_drapes, solver_name):
    """Case 7 as ``party validate`` runs it: fabrics B, C and F (measured DC 49.8, 50.7 and
    28.3 %, 5, 5 and 7 folds), the mean of three specimens within 8 DC points and 1 fold of the
    measurement, with either solver. Single specimens differ by up to 2 folds (the implicit
    solver_name's B: 7, 5 and 6), so the first alone does not decide the case. With the hysteresis
    element's stuck spring at 5 times the bending (now 20) B and C had 6 folds, F 8.3 to 8.7,
    and the implicit solver's B, at 1/300 s, 7."""
    for name in ("measured_B", "measured_C", "measured_F"):
        drapes, dc, nodes = measured_drapes(name, solver_name)
        summary = cusick.summarize(drapes)
        assert abs(summary["dc_percent"] - dc) <= cusick.DC_TOLERANCE, name
        assert abs(summary["nodes"] - nodes) <= cusick.NODE_TOLERANCE, name
