"""The paper's experiment 2 at --quick resolution, run through the command line."""

import json
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image


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
