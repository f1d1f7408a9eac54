"""The paper's experiment 2 at --quick resolution, run through the command line."""

import json
import shutil
import subprocess
import sys

import numpy as np
import pytest
import trimesh
from PIL import Image

from party.scenes import dress


@pytest.fixture(scope="module")
def dress_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("dress")
    run = subprocess.run([sys.executable, "-m", "party.cli", "run", "dress", "--quick", "--out", str(out),
                          "--no-progress"], capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr
    return out, json.loads((out / "summary.json").read_text())


def test_dress_stays_outside_the_form_and_itself(dress_run):
    _, summary = dress_run
    assert summary["status"] == "finished"
    assert summary["body_penetrations"] == 0
    assert summary["cloth_crossings"] == 0
    assert summary["max_seam_gap_mm"] < 2.0
    assert summary["max_elongation"] < 1.0995 * 1.02


def test_dress_relaxation_energy_settles(dress_run):
    out, _ = dress_run
    log = json.loads((out / "relaxation.json").read_text())
    energy = np.array(log["sewing_energy_J"])[:, 1]
    assert energy[-1] < 1e-2 * energy[0]


def test_dress_pictures(dress_run):
    out, summary = dress_run
    for view in ("front", "side", "back"):
        image = Image.open(out / "images" / f"final_{view}.png")
        assert min(image.size) >= 1024
        pixels = np.asarray(image.convert("RGB"), float)
        assert pixels.std() > 10  # something was drawn
    assert Image.open(out / "images" / "sleeve_fall.gif").n_frames == summary["frames"]
    assert (out / "images" / "wireframe_sequence.png").exists()
    # the three views differ
    a, b = (np.asarray(Image.open(out / "images" / f"final_{v}.png").convert("L"), float) for v in ("front", "side"))
    assert np.abs(a - b).mean() > 5


class Stop(Exception):
    pass


def test_a_resumed_dress_takes_its_sewing_from_sewn_npz(dress_run):
    """Resumed, the dress does not sew again: its model starts where the run's did (its frame 0),
    and its summary keeps the sewing's log."""
    out, summary = dress_run
    stages = []
    scene = dress.build(dress.Settings(quick=True), out=out, resume=True,
                        on_save=lambda stage, step: stages.append(stage))
    assert stages == []  # nothing sewn, so nothing saved
    frame_0 = trimesh.load(out / "frames" / "frame_000000.ply", process=False).vertices
    assert np.array_equal(scene.model.state().positions(), frame_0)
    assert scene.summary["relaxation"] == summary["relaxation"]


def test_a_dress_stopped_while_sewing_goes_on_from_its_last_stage(dress_run, tmp_path):
    """Stopped after its closing stage, the dress resumed does not place its panels again and
    ends sewn where a run through did, bit for bit."""
    out, _ = dress_run

    def stop_once_closed(stage, step):
        if stage == "closed":
            raise Stop

    with pytest.raises(Stop):
        dress.build(dress.Settings(quick=True), out=tmp_path, on_save=stop_once_closed)
    stages = []
    scene = dress.build(dress.Settings(quick=True), out=tmp_path, resume=True,
                        on_save=lambda stage, step: stages.append(stage))
    assert stages[0] == "settling" and "sewn" not in stages  # the panels were not placed and sewn again
    frame_0 = trimesh.load(out / "frames" / "frame_000000.ply", process=False).vertices
    assert np.array_equal(scene.model.state().positions(), frame_0)


def test_a_finished_dress_resumed_keeps_its_summary(dress_run, tmp_path):
    """Resuming a run that had finished takes no step and writes the same summary."""
    out, summary = dress_run
    copy = shutil.copytree(out, tmp_path / "copy")
    run = subprocess.run([sys.executable, "-m", "party.cli", "run", "dress", "--quick", "--out", str(copy),
                          "--no-progress", "--resume"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert json.loads((copy / "summary.json").read_text()) == summary


def test_resuming_another_dress_sewing_is_refused_in_one_line(dress_run):
    """Resumed in another fabric, the dress refuses the sewing it kept: one line names the file
    and what differs, exit 1."""
    out, _ = dress_run
    run = subprocess.run([sys.executable, "-m", "party.cli", "run", "dress", "--quick", "--out", str(out),
                          "--no-progress", "--resume", "--fabric", "cotton"], capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 1
    assert run.stderr.strip() == (f"error: {out / 'sewn.npz'} belongs to another dress sewing (different fabric); "
                                  "remove it or drop --resume")
