"""Experiment 1 (figure 11) at a coarse resolution, through the CLI as a user runs it."""

import json
import subprocess
import sys

import numpy as np
import pytest
import trimesh

from party.scenes.rod_wind import ROD_HEIGHT, ROD_RADIUS


@pytest.fixture(scope="module")
def rod_wind_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("rod-wind")
    result = subprocess.run([sys.executable, "-m", "party.cli", "run", "rod-wind", "--out", str(out),
                             "--spacing", "0.025", "--duration", "0.4", "--no-progress"],
                            capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, result.stderr
    return out


def test_no_penetration_no_crossing_and_elongation_bounded(rod_wind_run):
    summary = json.loads((rod_wind_run / "summary.json").read_text())
    assert summary["status"] == "finished"
    assert summary["body_penetrations"] == 0
    assert summary["cloth_crossings"] == 0
    assert 1.0 <= summary["max_elongation"] <= 1.0 + 0.0995 + 1e-4
    assert summary["steps"] == 4000 and summary["simulated_seconds"] == pytest.approx(0.4)
    assert summary["nodes"] == len(trimesh.load(rod_wind_run / "frames" / "frame_000000.ply", process=False).vertices)


def test_outputs_are_laid_out_as_documented(rod_wind_run):
    frames = sorted((rod_wind_run / "frames").glob("frame_*.ply"))
    assert len(frames) == 21  # t = 0 and every 0.02 s
    assert (rod_wind_run / "colliders" / "rod.ply").exists()
    for name in ("sequence.png", "final.png"):
        assert (rod_wind_run / "images" / name).stat().st_size > 10_000


def test_wind_blows_the_cloth_leeward_and_the_halves_meet(rod_wind_run):
    first = np.asarray(trimesh.load(rod_wind_run / "frames" / "frame_000000.ply", process=False).vertices)
    last = np.asarray(trimesh.load(sorted((rod_wind_run / "frames").glob("frame_*.ply"))[-1], process=False).vertices)
    # the cloth's centre of mass moves downwind (+x), and stays hung on the rod
    assert last[:, 0].mean() > first[:, 0].mean() + 0.02
    assert last[:, 2].max() > ROD_HEIGHT + ROD_RADIUS
    # the windward half (started at x < 0) is pushed across, onto the leeward half's side
    windward = first[:, 0] < 0
    low = first[:, 2] < ROD_HEIGHT - 0.2
    assert last[windward & low, 0].mean() > 0.0
