"""``party drape --resume``: a drape stopped while it sews or drapes goes on from its checkpoint."""

import json
import signal
from dataclasses import replace
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import wait_for_file

from party.body.load import load_body
from party.errors import InvalidInput
from party.fabric import fabric_by_name
from party.garment.assemble import assemble
from party.pattern import load_pattern
from party.garment import sewing
from party.scenes import drape as drape_module
from party.scenes.drape import DrapeSettings

DRESS = Path(drape_module.__file__).parents[1] / "data" / "patterns" / "dress_sleeves.json"
SPACING = 0.03


class Stop(Exception):
    pass


@pytest.mark.slow
def test_a_stopped_drape_resumes_from_its_checkpoint_without_sewing_again(tmp_path, solver_name):
    """Stopped after its second save while draping, the drape leaves only its checkpoint; resumed,
    it does not sew again, goes on from the saved step to rest, with nothing through the body or
    itself, and counts the sewing it did before."""
    out = tmp_path / "out"
    settings = DrapeSettings(spacing=SPACING, solver=solver_name, images=False, progress=False, checkpoint_seconds=0.0)
    saves = []

    def stop_after_two(stage, step):
        if stage == "draping":
            saves.append(step)
            if len(saves) == 2:
                raise Stop

    flannel = fabric_by_name("wool_flannel")
    with pytest.raises(Stop):
        drape_module.drape(DRESS, "M", flannel, out, settings, on_save=stop_after_two)
    assert sorted(p.name for p in out.iterdir()) == [".party", "checkpoint.npz"]
    with np.load(out / "checkpoint.npz") as saved:
        assert int(saved["draping_step"]) == saves[-1]
        sewing = int(saved["sewn_iterations"]) + int(saved["sewn_settling_iterations"])
        earlier = float(saved["wall_seconds"])

    stages = []
    summary = drape_module.drape(DRESS, "M", flannel, out, replace(settings, resume=True),
                                 on_save=lambda stage, step: stages.append(stage))
    assert set(stages) == {"draping"}  # not sewn again
    relaxation = summary["relaxation"]
    assert relaxation["at_rest"] and relaxation["draping_steps"] > saves[-1]
    assert relaxation["sewing_iterations"] == sewing
    assert summary["wall_seconds"] > earlier
    assert summary["body_penetrations"] == 0 and summary["cloth_crossings"] == 0
    assert summary["max_elongation"] < 1.0 + flannel.strain_limit + 0.02
    assert not (out / "checkpoint.npz").exists()
    logged = json.loads((out / "relaxation.json").read_text())["draping_energy_J"]
    assert [step for step, _ in logged] == sorted({step for step, _ in logged})  # one log, on from the saved one
    assert logged[0][0] <= saves[0]


@pytest.mark.slow
def test_a_drape_stopped_while_sewing_goes_on_from_the_last_stage_it_finished(tmp_path):
    """Stopped after the closing stage of its sewing, a drape resumed does not place the panels
    again (the first stage's start), settles, drapes and writes a clean result."""
    out = tmp_path / "out"
    settings = DrapeSettings(spacing=SPACING, solver="implicit", images=False, progress=False)

    def stop_once_closed(stage, step):
        if stage == "closed":
            raise Stop

    flannel = fabric_by_name("wool_flannel")
    with pytest.raises(Stop):
        drape_module.drape(DRESS, "M", flannel, out, settings, on_save=stop_once_closed)
    with np.load(out / "checkpoint.npz") as saved:
        assert str(saved["sewing_stage"]) == "closed" and "sewn_points" not in saved

    stages = []
    summary = drape_module.drape(DRESS, "M", flannel, out, replace(settings, resume=True),
                                 on_save=lambda stage, step: stages.append(stage))
    assert stages[0] == "settling" and "sewn" not in stages  # the panels were not placed and sewn again
    assert summary["relaxation"]["at_rest"] and summary["max_seam_gap_mm"] < 1.0
    assert summary["body_penetrations"] == 0 and summary["cloth_crossings"] == 0


def test_a_sewing_resumed_after_its_first_stage_or_closing_ends_as_one_run_through():
    """Each stage starts from where the last left the cloth, at rest, with models and solvers of
    its own: a sewing resumed after its first stage, its closing or its last settling round ends
    on the same positions, bit for bit, with the same seam gaps and logs. (Resumed after an
    earlier settling round, the settling's collision searches start afresh, which may change
    the last bits.)"""
    garment = assemble(load_pattern(DRESS), SPACING)
    body, flannel = load_body("M"), fabric_by_name("wool_flannel")
    stages = []
    whole = sewing.sew(garment, body, flannel, on_stage=stages.append)
    assert [(s.stage, s.rounds) for s in stages][:2] == [("sewn", 0), ("closed", 0)]
    assert [s.rounds for s in stages[2:]] == list(range(1, len(stages) - 1)) and stages[2].stage == "settling"
    for stage in stages[:2] + stages[-1:]:
        again = sewing.sew(garment, body, flannel, resume=stage)
        assert np.array_equal(again.points, whole.points), stage.stage
        assert np.array_equal(again.seam_gaps, whole.seam_gaps)
        assert again.relaxation.energy == whole.relaxation.energy and again.settling.energy == whole.settling.energy
        assert again.settling.iterations == whole.settling.iterations


def test_resuming_from_another_drapes_checkpoint_is_refused_in_one_line(tmp_path):
    """A drape stopped once sewn, then resumed in another fabric: one line names the checkpoint
    and what differs, exit 1, and the checkpoint is kept."""
    out = tmp_path / "out"
    command = [sys.executable, "-m", "party.cli", "drape", str(DRESS), "--out", str(out), "--spacing-mm",
               str(1000 * SPACING), "--no-images", "--no-progress"]
    running = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wait_for_file(out / "checkpoint.npz", running)
    running.send_signal(signal.SIGKILL)
    running.wait()
    assert (out / "checkpoint.npz").exists()
    result = subprocess.run(command + ["--fabric", "cotton", "--resume"], capture_output=True, text=True, timeout=300)
    assert result.returncode == 1
    assert result.stderr.strip() == (f"error: {out / 'checkpoint.npz'} belongs to another drape (different fabric); "
                                     "remove it or drop --resume")
    assert sorted(p.name for p in out.iterdir()) == [".party", "checkpoint.npz"]


@pytest.mark.slow
def test_a_drape_past_its_time_limit_keeps_its_result_and_checkpoint_and_a_resume_goes_on(tmp_path):
    out = tmp_path / "out"
    settings = DrapeSettings(spacing=SPACING, images=False, progress=False, time_limit=0.5)
    flannel = fabric_by_name("wool_flannel")
    first = drape_module.drape(DRESS, "M", flannel, out, settings)
    assert first["timed_out"] and not first["quality"]["passed"]
    assert "ran past its time limit of 0.5 s and was stopped there" in first["quality"]["reasons"]
    assert {"garment.obj", "summary.json", "checkpoint.npz"} <= {p.name for p in out.iterdir()}
    with np.load(out / "checkpoint.npz") as saved:
        assert int(saved["draping_step"]) == first["relaxation"]["draping_steps"]

    second = drape_module.drape(DRESS, "M", flannel, out, replace(settings, resume=True, time_limit=900.0))
    assert not second["timed_out"]
    assert not any(r.startswith("ran past") for r in second["quality"]["reasons"])
    assert second["relaxation"]["draping_steps"] > first["relaxation"]["draping_steps"]
    assert second["wall_seconds"] > first["wall_seconds"]
    assert not (out / "checkpoint.npz").exists()


def test_a_time_limit_that_is_not_a_positive_number_is_refused_in_one_line():
    with pytest.raises(InvalidInput, match=r"^--time-limit must be a positive number of seconds, got -1$"):
        DrapeSettings(time_limit=-1.0)
