"""Bad input and blow-ups: one line naming the problem, non-zero exit, results kept."""

import json
import signal
import subprocess
import sys

import numpy as np
import pytest
from conftest import wait_for_file
import warp as wp

from party.errors import InvalidInput, SimulationUnstable
from party.fabric import wool_flannel
from party.meshing import rectangular_net
from party.model import ModelBuilder
from party.scenes.runner import run_scene
from party.scenes.scene import Scene
from party.solvers import SolverExplicit


def party(*args):
    return subprocess.run([sys.executable, "-m", "party.cli", *args], capture_output=True, text=True, timeout=600)


@pytest.mark.parametrize("args,message", [
    (["--dt", "0"], "error: time step must be positive and finite, got 0.0"),
    (["--dt", "-1e-4"], "error: time step must be positive and finite, got -0.0001"),
    (["--duration", "0"], "error: duration must be positive and finite, got 0.0"),
    (["--dt", "0.001"], "error: time step 0.001 s exceeds this net's explicit stability limit"),
    (["--spacing", "-0.01"], "error: spacing must be positive"),
    (["--wind", "nan"], "error: --wind must be a finite speed in m/s, got nan"),
])
def test_bad_run_options(tmp_path, args, message):
    result = party("run", "rod-wind", "--out", str(tmp_path / "o"), "--no-progress", *args)
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(message), result.stderr
    assert "Traceback" not in result.stderr


@pytest.mark.parametrize("scene", ["dress", "rod-wind", "sphere-drop"])
@pytest.mark.parametrize("args,message", [
    (["--duration", "-1"], "error: duration must be positive and finite, got -1.0"),
    (["--duration", "inf"], "error: duration must be positive and finite, got inf"),
    (["--dt", "-1e-4"], "error: time step must be positive and finite, got -0.0001"),
    (["--dt", "inf"], "error: time step must be positive and finite, got inf"),
])
def test_every_scene_rejects_a_time_that_is_not_positive_and_finite_before_setting_up(tmp_path, scene, args, message):
    result = party("run", scene, "--quick", "--out", str(tmp_path / "o"), "--no-progress", *args)
    assert result.returncode == 1
    assert result.stderr.strip() == message
    assert not (tmp_path / "o").exists()


def test_unknown_scene():
    result = party("run", "no-such-scene", "--out", "x")
    assert result.returncode == 1
    assert result.stderr.strip() == "error: unknown scene 'no-such-scene'; known: dress, rod-wind, sphere-drop"


@pytest.mark.skipif(wp.is_cuda_available(), reason="this machine has a CUDA device")
def test_cuda_asked_for_where_there_is_none(tmp_path):
    result = party("run", "sphere-drop", "--grid", "8", "--device", "cuda", "--out", str(tmp_path / "o"))
    assert result.returncode == 1
    assert result.stderr.strip() == "error: device 'cuda' requested but no CUDA device is available"
    assert not (tmp_path / "o").exists()


def test_unknown_option_is_a_usage_error():
    result = party("validate", "--no-such-option")
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert result.stderr.strip().splitlines()[-1] == "Error: No such option: --no-such-option"


def test_scenes_are_listed():
    result = party("scenes")
    assert result.returncode == 0 and result.stdout.startswith("rod-wind")


def test_nan_position_is_refused():
    net = rectangular_net(0.1, 0.1, 0.05)
    pts = np.c_[net.uv, np.zeros(net.node_count)]
    pts[4, 1] = np.nan
    with pytest.raises(InvalidInput, match="node 4 has a non-finite position"):
        ModelBuilder().add_cloth(net, wool_flannel(), pts)


def test_pinned_index_out_of_range():
    net = rectangular_net(0.1, 0.1, 0.05)
    b = ModelBuilder()
    b.add_cloth(net, wool_flannel(), np.c_[net.uv, np.zeros(net.node_count)])
    with pytest.raises(InvalidInput, match=r"pinned node index out of range \[0, 9\)"):
        b.pin([3, 9])


def test_blow_up_stops_with_advice_and_keeps_frames(tmp_path):
    """A damper far too strong for the step (c dt / m = 40), stepped by a solver that states no
    stability limit (so the run cannot refuse the dt up front): the runner notices the blow-up."""
    b = ModelBuilder(gravity=(0.0, 0.0, -9.8))
    net = rectangular_net(0.1, 0.1, 0.01)
    cloth = b.add_cloth(net, wool_flannel().with_(damping=4.0e5), np.c_[net.uv, np.zeros(net.node_count)])
    b.pin(cloth.nodes([0]))
    model = b.finalize("cpu")
    pts = model.state().positions()
    pts += np.random.default_rng(1).normal(0, 1e-4, pts.shape)
    model.node_rest_points.assign(pts.astype(np.float32))
    explicit = SolverExplicit(model, collision=None)
    assert explicit.critical_time_step() < 1e-4  # the damped limit would refuse this dt

    class NoStatedLimit:
        name = "unstated"
        step = explicit.step
        flush = explicit.flush

        def stable_time_step(self) -> float:
            return float("inf")

    scene = Scene("blow-up", model, NoStatedLimit(), dt=1e-4, duration=0.1, frame_interval=0.002)
    with pytest.raises(SimulationUnstable, match=r"simulation became unstable .* try a smaller --dt, e.g. 5e-05"):
        run_scene(scene, tmp_path, progress=False)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "unstable"
    assert (tmp_path / "frames" / "frame_000000.ply").exists()


def test_resume_continues_where_it_stopped(tmp_path):
    from party.scenes.rod_wind import Settings, build

    first = run_scene(build(Settings(spacing=0.05, duration=0.02, frame_interval=0.01)), tmp_path, progress=False)
    resumed = run_scene(build(Settings(spacing=0.05, duration=0.04, frame_interval=0.01)), tmp_path, resume=True, progress=False)
    run_scene(build(Settings(spacing=0.05, duration=0.04, frame_interval=0.01)), tmp_path / "fresh", progress=False)
    assert first["steps"] == 200 and resumed["steps"] == 400
    import trimesh

    a = trimesh.load(tmp_path / "frames" / "frame_000004.ply", process=False).vertices
    b = trimesh.load(tmp_path / "fresh" / "frames" / "frame_000004.ply", process=False).vertices
    assert np.allclose(a, b, atol=1e-6)


def test_resume_with_nothing_to_resume_says_so_and_runs_from_the_start(tmp_path):
    out = tmp_path / "o"
    result = party("run", "sphere-drop", "--grid", "16", "--duration", "0.02", "--out", str(out), "--no-progress",
                   "--resume")
    assert result.returncode == 0, result.stderr
    said = " ".join(result.stdout.split())
    assert said.startswith(f"nothing to resume: no checkpoint.npz in {out}; the run starts from its first frame ")
    assert json.loads((out / "summary.json").read_text())["steps"] > 0


def test_a_duration_within_a_frame_ends_the_run_there(tmp_path):
    """The run simulates its duration in whole steps, its last frame shorter where the
    duration ends within it (0.025 s of 1e-4 s steps in frames of 0.01 s: 250 steps, frames at
    0, 0.01, 0.02 and 0.025 s); resumed for 0.04 s, it goes on from 0.025 s to 0.04 s."""
    from party.scenes.rod_wind import Settings, build

    summary = run_scene(build(Settings(spacing=0.05, duration=0.025, frame_interval=0.01)), tmp_path, progress=False)
    assert summary["steps"] == 250 and summary["simulated_seconds"] == pytest.approx(0.025)
    assert summary["frames"] == 4
    assert sorted(p.name for p in (tmp_path / "frames").iterdir())[-1] == "frame_000003.ply"
    resumed = run_scene(build(Settings(spacing=0.05, duration=0.04, frame_interval=0.01)), tmp_path, resume=True,
                        progress=False)
    assert resumed["steps"] == 400 and resumed["frames"] == 5
    with np.load(tmp_path / "checkpoint.npz") as saved:
        assert float(saved["time"]) == pytest.approx(0.04)


def test_ctrl_c_says_how_to_go_on_and_exits_130(tmp_path):
    """A run stopped by Ctrl-C (SIGINT) once it has written a checkpoint ends with one line
    saying how to go on, exit status 130, and the checkpoint kept."""
    out = tmp_path / "o"
    running = subprocess.Popen([sys.executable, "-m", "party.cli", "run", "sphere-drop", "--grid", "32", "--duration",
                                "100", "--out", str(out), "--no-progress"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    wait_for_file(out / "checkpoint.npz", running)
    running.send_signal(signal.SIGINT)
    _, stderr = running.communicate(timeout=120)
    assert running.returncode == 130
    assert stderr.strip().splitlines()[-1] == "interrupted; rerun with --resume to continue"
    assert "Traceback" not in stderr
    assert (out / "checkpoint.npz").exists()


def test_help_gives_the_units_of_each_quantity():
    """Brackets in help texts are units, not markup: `[s]` once vanished as a style tag."""
    result = party("run", "--help")
    assert result.returncode == 0
    text = " ".join(result.stdout.split())
    for phrase in ("Node spacing of the net [m]", "Time step [s]", "Wind speed [m/s]"):
        assert phrase in text, phrase
