"""``party drape --resume``: a drape stopped while it drapes goes on from its checkpoint."""

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from party.fabric import fabric_by_name
from party.scenes import drape as drape_module
from party.scenes import drape_checkpoint

DRESS = Path(drape_module.__file__).parents[1] / "data" / "patterns" / "dress_sleeves.json"
SPACING = 0.03


class Stop(Exception):
    pass


@pytest.mark.parametrize("solver", ["explicit", "implicit"])
def test_a_stopped_drape_resumes_from_its_checkpoint_without_sewing_again(tmp_path, monkeypatch, solver):
    """Stopped after its second save while draping, the drape leaves only its checkpoint; resumed,
    it does not sew again, goes on from the saved step to rest, with nothing through the body or
    itself, and counts the sewing it did before."""
    out = tmp_path / "out"
    monkeypatch.setattr(drape_checkpoint, "SAVE_SECONDS", 0.0)
    save = drape_checkpoint.DrapeCheckpoint.save_draping
    saves = []

    def save_then_stop(self, state, step, energy, wall_seconds):
        save(self, state, step, energy, wall_seconds)
        saves.append(step)
        if len(saves) == 2:
            raise Stop

    monkeypatch.setattr(drape_checkpoint.DrapeCheckpoint, "save_draping", save_then_stop)
    flannel = fabric_by_name("wool_flannel")
    with pytest.raises(Stop):
        drape_module.drape(DRESS, "M", flannel, out, spacing=SPACING, solver=solver, images=False, progress=False)
    assert sorted(p.name for p in out.iterdir()) == ["checkpoint.npz"]
    with np.load(out / "checkpoint.npz") as saved:
        assert int(saved["draping_step"]) == saves[-1]
        sewing = int(saved["sewn_iterations"]) + int(saved["sewn_settling_iterations"])
        earlier = float(saved["wall_seconds"])

    monkeypatch.setattr(drape_checkpoint.DrapeCheckpoint, "save_draping", save)
    monkeypatch.setattr(drape_module, "sew", lambda *args, **kwargs: pytest.fail("sewed again"))
    summary = drape_module.drape(DRESS, "M", flannel, out, spacing=SPACING, solver=solver, images=False,
                                 progress=False, resume=True)
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


def test_resuming_from_another_drapes_checkpoint_is_refused_in_one_line(tmp_path):
    """A drape stopped once sewn, then resumed in another fabric: one line names the checkpoint
    and what differs, exit 1, and the checkpoint is kept."""
    out = tmp_path / "out"
    command = [sys.executable, "-m", "party.cli", "drape", str(DRESS), "--out", str(out), "--spacing-mm",
               str(1000 * SPACING), "--no-images", "--no-progress"]
    running = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 300
    while not (out / "checkpoint.npz").exists() and running.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    running.send_signal(signal.SIGKILL)
    running.wait()
    assert (out / "checkpoint.npz").exists()
    result = subprocess.run(command + ["--fabric", "cotton", "--resume"], capture_output=True, text=True, timeout=300)
    assert result.returncode == 1
    assert result.stderr.strip() == (f"error: {out / 'checkpoint.npz'} belongs to another drape (different fabric); "
                                     "remove it or drop --resume")
    assert sorted(p.name for p in out.iterdir()) == ["checkpoint.npz"]
