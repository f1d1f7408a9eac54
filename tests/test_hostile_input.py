"""The hostile-input campaign's cases (../shared/research/bad-input-campaign.md), one test each:
party never deletes a user's files, never blows up memory or time, never passes a wrong result
silently, and answers every bad input with one line (exit 1), never a traceback."""

import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from party.errors import InvalidInput
from party.output.folder import MARKER, STAGING_PREFIX, open_output
from party.resources import Footprint, check_memory

SHARED = Path(__file__).resolve().parents[2] / "shared"
GC = SHARED / "data" / "garmentcode"
BODY = GC / "bodies" / "mean_all.obj"
TSHIRT = GC / "patterns" / "tshirt_mean_specification.json"
HOODY = GC / "patterns" / "hoody_mean_specification.json"
JUMPSUIT = GC / "patterns" / "js_mean_all_specification.json"
needs_shared = pytest.mark.skipif(not GC.exists(), reason="../shared/data/garmentcode is not present")

MEMORY_BOUND = 1.5e9
"""Peak resident memory [bytes] a refused input may cost (a drape's set-up is about 0.5 GB)."""


def party(*args, cwd=None, env=None, timeout=600):
    """Run the CLI; returns (exit status, stdout, stderr)."""
    command = [sys.executable, "-m", "party.cli", *map(str, args)]
    child = subprocess.Popen(command, cwd=cwd, env={**os.environ, **(env or {})}, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    try:
        out, err = child.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        child.kill()
        raise
    return child.returncode, out, err


def run(*args, **kwargs):
    """The CLI's exit status and its last line on stderr (or stdout where stderr is empty)."""
    status, out, err = party(*args, **kwargs)
    assert "Traceback" not in err and "Traceback" not in out, err
    lines = (err.strip() or out.strip()).splitlines()
    return status, lines[-1] if lines else ""


def peak_memory(*args, env=None):
    """Exit status, last stderr line and peak resident memory [bytes] of a CLI run."""
    command = [sys.executable, "-m", "party.cli", *map(str, args)]
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                             env={**os.environ, **(env or {})})
    _, status, usage = os.wait4(child.pid, 0)
    err = child.stderr.read()
    assert "Traceback" not in err, err
    return os.waitstatus_to_exitcode(status), (err.strip().splitlines() or [""])[-1], usage.ru_maxrss * 1024.0


def users_folder(path: Path) -> Path:
    """A folder holding a user's own work."""
    (path / "photos").mkdir(parents=True)
    (path / "thesis.tex").write_text("\\chapter{Drape}\n")
    (path / "photos" / "fitting.jpg").write_bytes(b"\xff\xd8jpeg")
    return path


def intact(path: Path) -> bool:
    return ((path / "thesis.tex").read_text() == "\\chapter{Drape}\n"
            and (path / "photos" / "fitting.jpg").read_bytes() == b"\xff\xd8jpeg")


def garmentcode(tmp_path: Path, change, name="p.json") -> Path:
    doc = json.loads(HOODY.read_text())
    change(doc)
    path = tmp_path / name
    path.write_text(json.dumps(doc))
    return path


# -- data loss -------------------------------------------------------------------------------

@needs_shared
def test_drape_into_a_users_folder_is_refused_and_leaves_it_intact(tmp_path):
    folder = users_folder(tmp_path / "userfolder")
    status, last = run("drape", TSHIRT, "--body", BODY, "--out", folder, "--spacing-mm", 40, "--no-progress")
    assert status == 1
    assert last == (f"error: --out {folder} holds files party did not write (photos/, thesis.tex); choose another "
                    "folder, or pass --overwrite to write party's results beside them (only party's own files are "
                    "replaced)")
    assert intact(folder) and sorted(p.name for p in folder.iterdir()) == ["photos", "thesis.tex"]


@needs_shared
@pytest.mark.parametrize("out", [".", ""])
def test_drape_into_the_current_folder_is_refused(tmp_path, out):
    folder = users_folder(tmp_path / "cwd")
    status, last = run("drape", TSHIRT, "--body", BODY, "--out", out, "--spacing-mm", 40, "--no-progress", cwd=folder)
    assert status == 1
    assert last.startswith("error: --out")
    assert "current folder" in last or "empty" in last
    assert intact(folder) and sorted(p.name for p in folder.iterdir()) == ["photos", "thesis.tex"]


@pytest.mark.parametrize("command", [["run", "sphere-drop", "--quick"], ["validate", "--case", "restitution", "--quick"]])
@pytest.mark.parametrize("where", ["parent", "home", "root"])
def test_every_command_refuses_a_folder_above_the_current_or_the_home_folder(tmp_path, command, where):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    out = {"parent": "..", "home": "~", "root": "/"}[where]
    status, last = run(*command, "--out", out, cwd=work)
    assert status == 1
    assert last.startswith(f"error: --out {out}: that is the ")


def test_run_and_validate_refuse_a_users_folder_but_write_beside_it_with_overwrite(tmp_path):
    for command, produced in ((["run", "sphere-drop", "--grid", 8, "--duration", 0.1, "--no-progress"], "summary.json"),
                              (["validate", "--case", "restitution", "--quick"], "results.json")):
        folder = users_folder(tmp_path / command[0])
        status, last = run(*command, "--out", folder)
        assert status == 1 and "holds files party did not write (photos/, thesis.tex)" in last
        assert sorted(p.name for p in folder.iterdir()) == ["photos", "thesis.tex"]
        status, last = run(*command, "--out", folder, "--overwrite")
        assert status == 0, last
        assert intact(folder) and (folder / produced).exists() and (folder / MARKER).exists()


@needs_shared
def test_drape_with_overwrite_replaces_only_its_own_files(tmp_path):
    folder = users_folder(tmp_path / "userfolder")
    (folder / "garment.obj").write_text("an older drape's garment\n")
    (folder / "images").mkdir()
    (folder / "images" / "old.png").write_bytes(b"png")
    status, last = run("drape", TSHIRT, "--body", BODY, "--out", folder, "--spacing-mm", 40, "--no-progress",
                       "--no-images", "--overwrite")
    assert status == 0, last
    assert intact(folder)
    names = sorted(p.name for p in folder.iterdir())
    assert names == [MARKER, "body.obj", "garment.glb", "garment.obj", "photos", "relaxation.json", "summary.json",
                     "thesis.tex"]  # the old images/ went with the older drape; no staging folder stays
    assert (folder / "garment.obj").read_text() != "an older drape's garment\n"


def test_a_killed_runs_staging_folder_is_removed_by_the_next_run(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    (out / MARKER).write_text("{}")
    stale = out / f"{STAGING_PREFIX}4242"
    (stale / "images").mkdir(parents=True)
    (out / "summary.json.part").write_text("half")
    with open_output(out, "drape"):
        assert not stale.exists() and not (out / "summary.json.part").exists()


def test_a_refused_run_leaves_no_folder_behind(tmp_path):
    out = tmp_path / "new" / "o"
    status, last = run("run", "sphere-drop", "--quick", "--dt", "-1", "--out", out)
    assert status == 1 and last == "error: time step must be positive and finite, got -1.0"
    assert not (tmp_path / "new").exists()


# -- concurrent runs -------------------------------------------------------------------------

def test_a_second_run_into_a_folder_in_use_is_refused_naming_the_first(tmp_path):
    out = tmp_path / "o"
    with open_output(out, "run", description="sphere-drop"):
        status, last = run("run", "sphere-drop", "--quick", "--out", out, "--no-progress")
    assert status == 1
    assert last.startswith(f"error: --out {out} is in use by another party run (party run sphere-drop, process "
                           f"{os.getpid()}, started ")
    assert last.endswith("wait for it to finish or choose another folder")


def test_the_lock_goes_with_a_killed_process(tmp_path):
    """flock is released by the kernel when its holder dies, even by kill -9."""
    out = tmp_path / "o"
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time; from party.output.folder import open_output; "
                               f"f = open_output({str(out)!r}, 'run'); print('held', flush=True); time.sleep(600)"],
                              stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "held"
    with pytest.raises(InvalidInput, match="is in use by another party run"):
        open_output(out, "run")
    holder.send_signal(signal.SIGKILL)
    holder.wait()
    with open_output(out, "run"):
        pass


# -- memory and time -------------------------------------------------------------------------

@needs_shared
@pytest.mark.parametrize("case", ["all translations x100", "one panel 10 km away"])
def test_a_panel_far_from_the_body_is_refused_before_any_work(tmp_path, case):
    def change(doc):
        panels = doc["pattern"]["panels"]
        if case == "one panel 10 km away":
            panels["left_btorso"]["translation"] = [1e6, 0, 0]
        else:
            for panel in panels.values():
                panel["translation"] = [100 * t for t in panel["translation"]]
    pattern = garmentcode(tmp_path, change)
    status, last, peak = peak_memory("drape", pattern, "--body", BODY, "--out", tmp_path / "o", "--no-progress")
    assert status == 1
    assert "m from the body, farther than the garment's largest panel is across" in last
    assert last.endswith("check its translation, the file's units and the body's up axis (--up)")
    assert peak < MEMORY_BOUND and not (tmp_path / "o").exists()


@needs_shared
def test_a_flat_body_is_refused(tmp_path):
    import trimesh

    body = trimesh.load(BODY, process=False)
    body.vertices[:, 2] = 0.0
    body.export(tmp_path / "flat.obj")
    status, last, peak = peak_memory("drape", TSHIRT, "--body", tmp_path / "flat.obj", "--out", tmp_path / "o")
    assert status == 1
    assert last.startswith("error: collider 'flat' encloses almost no volume")
    assert peak < MEMORY_BOUND


def test_the_relief_search_holds_its_memory_at_any_reach():
    """The body's relief (the body-vertex test's set-up) runs in chunks of bounded pairs: at a
    reach that covers the whole sphere every vertex is every other's neighbour, yet the
    answer equals that of one search (and a rise of at most the sphere's diameter)."""
    from party.body import relief, sphere

    ball = sphere(0.3, subdivisions=3)
    rise, cosine = relief.vertex_relief(ball, 1.0, max_pairs=10**9)
    rise_chunked, cosine_chunked = relief.vertex_relief(ball, 1.0, max_pairs=5000)
    assert np.array_equal(rise, rise_chunked) and np.array_equal(cosine, cosine_chunked)
    assert rise.max() == pytest.approx(0.6, rel=1e-3) and cosine.min() == pytest.approx(-1.0, abs=1e-3)


def test_a_garment_too_fine_for_the_memory_is_refused_with_a_spacing_that_fits():
    footprint = Footprint(base=1e9, per_node=1e4)
    with pytest.raises(InvalidInput) as caught:
        check_memory(footprint, 2_000_000, 0.001, free=11e9)
    message = str(caught.value)
    assert message.startswith("about 2,000,000 nodes at --spacing-mm 1 would need about 21 GB of memory and this "
                              "machine has 9.9 GB free; use --spacing-mm ")
    fits = float(message.rsplit("--spacing-mm ", 1)[1].split()[0]) / 1000.0
    assert footprint.bytes(int(2_000_000 * (0.001 / fits) ** 2)) <= 0.9 * 11e9
    check_memory(footprint, 800_000, 0.0016, free=11e9)


@needs_shared
def test_a_one_millimetre_jumpsuit_is_refused_before_meshing(tmp_path):
    status, last, peak = peak_memory("drape", JUMPSUIT, "--body", BODY, "--out", tmp_path / "o", "--spacing-mm", 1,
                                     env={"PARTY_MAX_MEMORY": "16G"})
    assert status == 1
    assert last.startswith("error: about ") and "would need about" in last and last.endswith(" or more")
    assert peak < MEMORY_BOUND


@pytest.mark.parametrize("dt, duration", [("1e-12", "0.5"), ("2e-10", "0.5")])
def test_a_step_count_no_one_means_is_refused_naming_the_dt_that_would_do(tmp_path, dt, duration):
    """5e11 steps are refused before the first (even at a microsecond a step they would take
    days); 2.5e9 steps once the first steps have shown their pace."""
    status, last = run("run", "sphere-drop", "--grid", 8, "--dt", dt, "--duration", duration, "--out",
                       tmp_path / "o", "--no-progress", timeout=120)
    assert status == 1
    assert last.startswith(f"error: {round(float(duration) / float(dt)):,} steps of {float(dt):g} s would take about ")
    needed = float(last.split("use a --dt of at least ")[1].split()[0])
    assert needed > float(dt)


@pytest.mark.parametrize("key, value, unit, bounds", [("tensile_warp", "5e12", "N/m", "1-1e+06"),
                                                     ("areal_density", "30", "kg/m^2", "0.005-3"),
                                                     ("thickness", "3", "m", "0.0001-0.05")])
def test_a_fabric_outside_the_range_of_real_cloth_is_refused_with_the_range(tmp_path, key, value, unit, bounds):
    values = {"areal_density": "0.2", "tensile_warp": "500.0", "tensile_weft": "400.0", "damping": "30.0", key: value}
    (tmp_path / "f.toml").write_text("".join(f"{k} = {v}\n" for k, v in values.items()))
    status, last = run("run", "sphere-drop", "--quick", "--fabric", tmp_path / "f.toml", "--out", tmp_path / "o")
    assert (status, last) == (1, f"error: f.toml: fabric 'f': {key} = {float(value):g} {unit} is outside {bounds} {unit}, "
                                 "the range of real cloth")


# -- silent wrong results --------------------------------------------------------------------

@needs_shared
def test_a_garment_that_ends_off_the_body_fails_its_quality_gate_loudly(tmp_path):
    out = tmp_path / "o"
    status, out_text, err = party("drape", TSHIRT, "--body", BODY, "--up", "x", "--out", out, "--spacing-mm", 40,
                                     "--no-progress", "--no-images")
    assert status == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["quality"]["passed"] is False
    assert summary["body_distance_mm"]["nearest"] > 100.0
    assert summary["quality"]["reasons"][0].startswith("not on the body: its nearest node is ")
    assert err.strip().splitlines()[-1].startswith("warning: the drape missed its quality gates: not on the body")


def test_the_quality_gates_name_each_miss():
    from party.output.quality import drape_quality

    good = {"body_distance_mm": {"nearest": 3.0, "median": 44.0, "near_share": 0.6}, "body_penetrations": 0, "cloth_crossings": 0,
            "max_seam_gap_mm": 0.5, "seam_gaps_mm": {"a-b": 0.5}, "max_elongation": 1.1, "relaxation": {"at_rest": True},
            "time_limit_s": 600.0, "timed_out": False}
    assert drape_quality(good, 3e-3) == {"passed": True, "reasons": []}
    full_skirt = dict(good, body_distance_mm={"nearest": 3.0, "median": 206.0, "near_share": 0.21})
    assert drape_quality(full_skirt, 3e-3) == {"passed": True, "reasons": []}
    bad = {"body_distance_mm": {"nearest": 3.0, "median": 526.0, "near_share": 0.03}, "body_penetrations": 2, "cloth_crossings": 1, "max_seam_gap_mm": 450.0,
           "seam_gaps_mm": {"a-b": 0.5, "c-d": 450.0}, "max_elongation": 6.2, "relaxation": {"at_rest": False},
           "time_limit_s": 30.0, "timed_out": True,
           "where": {"stretched": {"panels": ["band"], "stage": "sewing"},
                     "inside": {"panels": ["skirt_f", "skirt_b"], "stage": "draping"},
                     "crossings": {"panels": ["hood"], "stage": "sewing"}}}
    assert drape_quality(bad, 3e-3)["reasons"] == [
        "not on the body: half its nodes are more than 526 mm from it",
        "2 nodes inside the body, in panel 'skirt_f' and panel 'skirt_b', in the draping",
        "1 cloth crossings, in panel 'hood', since the sewing", "seam c-d left open 450.0 mm by the sewing",
        "stretched to 6.20 times rest (at most 1.3), in panel 'band', since the sewing",
        "not at rest at the end of the draping", "ran past its time limit of 30 s and was stopped there"]


@pytest.mark.parametrize("change, differing", [
    (["--fabric", "silk"], "parameters: fabric"),
    (["--solver", "explicit", "--dt", "0.0001"], "dt, solver"),
    (["--self-collision", "off"], "self_collision"),
])
def test_resuming_another_runs_checkpoint_is_refused(tmp_path, change, differing):
    out = tmp_path / "o"
    first = ["run", "sphere-drop", "--grid", 8, "--duration", 0.1, "--out", out, "--no-progress"]
    assert run(*first)[0] == 0
    status, last = run("run", "sphere-drop", "--grid", 8, "--duration", 0.2, "--out", out, "--no-progress", "--resume",
                       *change)
    assert status == 1
    names = differing.split(": ")[-1]
    assert last == f"error: {out / 'checkpoint.npz'} belongs to another run (different {names}); remove it or drop --resume"


def resumable_scene(kind: str):
    """Small scenes whose interrupted frames fall where the solver's memory matters: cloth in
    contact with the sphere, self-collision and the crossing guard on, bending hysteresis, wind."""
    from party.fabric import library
    from party.scenes import rod_wind, sphere_drop

    if kind == "implicit":
        return sphere_drop.build(sphere_drop.Settings(grid=16, duration=0.4, solver="implicit")), 9
    if kind == "explicit":
        return sphere_drop.build(sphere_drop.Settings(grid=10, duration=0.3, solver="explicit", dt=1e-4)), 8
    if kind == "hysteresis":
        return sphere_drop.build(sphere_drop.Settings(grid=12, duration=0.3, solver="implicit",
                                                      fabric=library()["cotton"].with_(bending_hysteresis=2e-5))), 8
    return rod_wind.build(rod_wind.Settings(spacing=0.05, duration=0.063, frame_interval=0.0105)), 3  # frames of 105 steps: the
    # shielding, updated every 20 steps, is carried over a frame's end


@pytest.mark.parametrize("kind", ["implicit", "explicit", "hysteresis", "wind"])
def test_a_resumed_run_is_bit_for_bit_the_run_it_continues(tmp_path, kind):
    """Stopped after a frame (as by Ctrl-C) and resumed, a run writes the very frames an
    uninterrupted run writes (with the State alone in the checkpoint, the implicit and hysteresis
    runs differ from the frame after)."""
    import filecmp

    from party.scenes.runner import run_scene

    scene, stop_at = resumable_scene(kind)
    run_scene(scene, tmp_path / "whole", progress=False)

    def stop(frame):
        if frame == stop_at:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_scene(resumable_scene(kind)[0], tmp_path / "cut", progress=False, on_frame=stop)
    assert not (tmp_path / "cut" / "frames" / f"frame_{stop_at + 1:06d}.ply").exists()
    run_scene(resumable_scene(kind)[0], tmp_path / "cut", progress=False, resume=True)
    frames = sorted((tmp_path / "whole" / "frames").iterdir())
    assert len(frames) > stop_at + 1
    assert all(filecmp.cmp(f, tmp_path / "cut" / "frames" / f.name, shallow=False) for f in frames)


def test_a_run_killed_and_resumed_writes_the_frames_of_one_run_through(tmp_path):
    import filecmp

    args = ["run", "sphere-drop", "--grid", 16, "--duration", 1.0, "--no-progress"]
    assert run(*args, "--out", tmp_path / "whole")[0] == 0
    cut = tmp_path / "cut"
    running = subprocess.Popen([sys.executable, "-m", "party.cli", *map(str, args), "--out", str(cut)],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    from conftest import wait_for_file

    wait_for_file(cut / "frames" / "frame_000008.ply", running)
    running.send_signal(signal.SIGKILL)
    assert running.wait() == -signal.SIGKILL
    assert run(*args, "--out", cut, "--resume")[0] == 0
    frames = sorted((tmp_path / "whole" / "frames").iterdir())
    assert all(filecmp.cmp(f, cut / "frames" / f.name, shallow=False) for f in frames)


@pytest.mark.parametrize("args, message", [
    (["--quick", "--grid", "100000"], "error: --grid must lie in 2-1000 nodes per side, got 100000"),
    (["--quick", "--dt", "0.2"], "error: the duration 0.5 s is not a whole number of steps of 0.2 s (2.5 steps); give "
                                 "--duration 0.4 or 0.6, or a --dt that divides it"),
])
def test_an_option_a_run_would_not_honour_is_an_error(tmp_path, args, message):
    status, last = run("run", "sphere-drop", *args, "--out", tmp_path / "o", "--no-progress")
    assert (status, last) == (1, message)


def test_quick_keeps_a_grid_given_with_it(tmp_path):
    out = tmp_path / "o"
    assert run("run", "sphere-drop", "--quick", "--grid", 6, "--duration", 0.05, "--out", out, "--no-progress")[0] == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["parameters"]["grid"] == 6 and summary["simulated_seconds"] == pytest.approx(0.05)


@needs_shared
@pytest.mark.parametrize("flag, value", [("--units", "mm"), ("--seams", "x.seams.json")])
def test_dxf_only_options_on_a_json_pattern_are_refused(tmp_path, flag, value):
    status, last = run("drape", HOODY, "--body", BODY, flag, value, "--out", tmp_path / "o")
    assert status == 1
    assert last == (f"error: {flag} applies to DXF patterns only; {HOODY} is a JSON pattern, which gives its own units "
                    "and seams")


@pytest.mark.parametrize("threads", ["0", "-1", "two"])
def test_a_thread_count_below_one_is_refused(tmp_path, threads):
    status, last = run("run", "sphere-drop", "--quick", "--out", tmp_path / "o", env={"PARTY_THREADS": threads})
    assert (status, last) == (1, f"error: PARTY_THREADS must be a whole number of threads from 1, got '{threads}'")


# -- tracebacks ------------------------------------------------------------------------------

def read_only_folder(tmp_path: Path) -> Path:
    """A folder no one may write into, root included (immutable where root runs the tests)."""
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        (folder / "probe").touch()
    except PermissionError:
        return folder
    (folder / "probe").unlink()
    if subprocess.run(["chattr", "+i", str(folder)], capture_output=True).returncode != 0:
        return Path("/proc/party-read-only")
    return folder


@pytest.fixture
def read_only(tmp_path):
    folder = read_only_folder(tmp_path)
    yield folder
    if folder.is_relative_to(tmp_path):
        subprocess.run(["chattr", "-i", str(folder)], capture_output=True)
        folder.chmod(0o755)


@needs_shared
@pytest.mark.parametrize("command", ["drape", "run", "validate"])
@pytest.mark.parametrize("target", ["file", "read-only", "read-only/sub"])
def test_an_output_that_cannot_be_written_is_one_line_before_any_work(tmp_path, read_only, command, target):
    if target == "file":
        out = tmp_path / "existing_file.txt"
        out.write_text("mine\n")
    else:
        out = read_only / "sub" if target.endswith("sub") else read_only
    args = {"drape": ["drape", TSHIRT, "--body", BODY, "--spacing-mm", 40, "--no-progress"],
            "run": ["run", "sphere-drop", "--quick", "--no-progress"],
            "validate": ["validate", "--case", "restitution", "--quick"]}[command]
    status, last = run(*args, "--out", out, timeout=120)
    assert status == 1
    if target == "file":
        assert last == f"error: --out {out} is a file, not a folder; name a folder for the results"
        assert out.read_text() == "mine\n"
    else:
        assert last.startswith(f"error: --out {out}: cannot write there (")


@pytest.mark.parametrize("command", [["run", "sphere-drop", "--quick"], ["drape", "party/data/patterns/dress_sleeves.json"]])
def test_an_unknown_device_is_one_line(tmp_path, command):
    status, last = run(*command, "--device", "tpu", "--out", tmp_path / "o", cwd=Path(__file__).parents[1])
    assert (status, last) == (1, "error: unknown device 'tpu' in --device (expected cpu, cuda, cuda:N or auto)")


def test_a_truncated_run_checkpoint_is_one_line(tmp_path):
    out = tmp_path / "o"
    assert run("run", "sphere-drop", "--grid", 8, "--duration", 0.1, "--out", out, "--no-progress")[0] == 0
    data = (out / "checkpoint.npz").read_bytes()
    (out / "checkpoint.npz").write_bytes(data[: len(data) // 2])
    status, last = run("run", "sphere-drop", "--grid", 8, "--duration", 0.2, "--out", out, "--no-progress", "--resume")
    assert (status, last) == (1, f"error: {out / 'checkpoint.npz'} is damaged or not a party checkpoint (not a NumPy "
                                 "archive); remove it or drop --resume")


def test_a_truncated_sewing_checkpoint_is_one_line(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    (out / MARKER).write_text("{}")
    (out / "sewn.npz").write_bytes(b"PK\x03\x04 cut short")
    status, last = run("run", "dress", "--quick", "--out", out, "--no-progress", "--resume")
    assert (status, last) == (1, f"error: {out / 'sewn.npz'} is damaged or not a party checkpoint (not a NumPy "
                                 "archive); remove it or drop --resume")


@pytest.mark.parametrize("content", ["[1, 2]", '{"settings": 5}', '{"cases": "x"'])
def test_validate_resume_from_a_file_that_is_no_record_warns_and_runs_every_case(tmp_path, content):
    out = tmp_path / "v"
    out.mkdir()
    (out / MARKER).write_text("{}")
    (out / "results.json").write_text(content)
    status, out_text, err = party("validate", "--case", "restitution", "--quick", "--resume", "--out", out)
    assert status == 0 and "Traceback" not in err
    assert "results.json is not a validation record" in err or "results.json was written with other settings" in err
    assert json.loads((out / "results.json").read_text())["cases"][0]["case"] == "restitution"


# -- unclear errors --------------------------------------------------------------------------

@needs_shared
def test_body_unit_advice_names_the_body_flag(tmp_path):
    import trimesh

    body = trimesh.load(BODY, process=False)
    body.vertices *= 1e6
    body.export(tmp_path / "huge.obj")
    status, last = run("drape", TSHIRT, "--body", tmp_path / "huge.obj", "--out", tmp_path / "o")
    assert status == 1 and last.endswith("pass --body-units")
    status, last = run("drape", TSHIRT, "--body", tmp_path / "huge.obj", "--body-units", "m", "--out", tmp_path / "o")
    assert status == 1 and last.endswith("check --body-units and --up")


@needs_shared
@pytest.mark.parametrize("case, change, message", [
    ("NaN vertex", lambda d: d["pattern"]["panels"]["left_btorso"]["vertices"][2].__setitem__(0, float("nan")),
     "panel 'left_btorso': vertex 2 is not a finite number"),
    ("zero area", lambda d: d["pattern"]["panels"]["left_hood"].update(
        vertices=[[0, 0], [10, 0], [20, 0], [30, 0], [40, 0]],
        edges=[{"endpoints": [k, (k + 1) % 5]} for k in range(5)]),
     "panel 'left_hood': outline encloses no area"),
    ("stitch to itself", lambda d: d["pattern"]["stitches"].__setitem__(0, [d["pattern"]["stitches"][0][0]] * 2),
     "joins an edge to itself"),
    ("panels as a list", lambda d: d["pattern"].__setitem__("panels", [1, 2]),
     "pattern.panels must be a table of panels by name, got a list"),
    ("rotation as strings", lambda d: d["pattern"]["panels"]["left_btorso"].__setitem__("rotation", [0, "ninety", 0]),
     "panel 'left_btorso': rotation (degrees) must be 3 numbers, got [0, 'ninety', 0]"),
])
def test_pattern_errors_name_the_file_and_the_part(tmp_path, case, change, message):
    pattern = garmentcode(tmp_path, change)
    status, last = run("drape", pattern, "--body", BODY, "--out", tmp_path / "o")
    assert status == 1
    assert last.startswith(f"error: {pattern}: ") and message in last


@needs_shared
def test_a_folder_is_not_a_pattern_or_a_body(tmp_path):
    (tmp_path / "dir.json").mkdir()
    assert run("drape", tmp_path / "dir.json", "--body", BODY, "--out", tmp_path / "o") == (
        1, f"error: {tmp_path / 'dir.json'} is a folder, not a pattern file (expected a .json or .dxf file)")
    assert run("drape", TSHIRT, "--body", tmp_path, "--out", tmp_path / "o")[1].startswith(
        f"error: {tmp_path} is a folder, not a body mesh file")


@needs_shared
def test_a_pattern_with_a_byte_order_mark_loads(tmp_path):
    from party.pattern import load_pattern

    path = tmp_path / "bom.json"
    path.write_bytes(b"\xef\xbb\xbf" + HOODY.read_bytes())
    assert len(load_pattern(path).panels) == len(load_pattern(HOODY).panels)


# -- no traceback, whatever the options ------------------------------------------------------

BAD_OPTIONS = [
    ["run"], ["run", "nosuch", "--out", "o"], ["run", "sphere-drop"], ["run", "sphere-drop", "--out", "o", "--grid", "x"],
    ["run", "sphere-drop", "--out", "o", "--grid", "1"], ["run", "sphere-drop", "--out", "o", "--duration", "nan"],
    ["run", "sphere-drop", "--out", "o", "--dt", "0"], ["run", "sphere-drop", "--out", "o", "--wind", "3"],
    ["run", "rod-wind", "--out", "o", "--grid", "8"], ["run", "rod-wind", "--out", "o", "--wind", "inf"],
    ["run", "rod-wind", "--out", "o", "--spacing", "0"], ["run", "sphere-drop", "--out", "o", "--self-collision", "x"],
    ["run", "sphere-drop", "--out", "o", "--solver", "rk4"], ["run", "sphere-drop", "--out", "o", "--fabric", "tweed"],
    ["run", "sphere-drop", "--out", "o", "--device", "cuda:x"], ["run", "dress", "--out", "o", "--spacing", "-1"],
    ["drape"], ["drape", "nosuch.json", "--out", "o"], ["drape", "x.txt", "--out", "o"],
    ["drape", "party/data/patterns/dress_sleeves.json", "--out", "o", "--spacing-mm", "0"],
    ["drape", "party/data/patterns/dress_sleeves.json", "--out", "o", "--spacing-mm", "1e9"],
    ["drape", "party/data/patterns/dress_sleeves.json", "--out", "o", "--body", "XL"],
    ["drape", "party/data/patterns/dress_sleeves.json", "--out", "o", "--up", "w"],
    ["drape", "party/data/patterns/dress_sleeves.json", "--out", "o", "--body-units", "furlong"],
    ["drape", "party/data/patterns/dress_sleeves.json", "--out", "o", "--solver", "verlet"],
    ["drape", "party/data/patterns/dress_sleeves.json", "--out", "o", "--fabric", "x.yaml"],
    ["validate", "--case", "nosuch"], ["validate", "--solver", "x"], ["validate", "--fabric", "tweed"],
    ["scenes", "--nope"], ["fabrics", "extra"], ["nosuchcommand"],
]


@pytest.mark.parametrize("args", BAD_OPTIONS, ids=lambda a: " ".join(a) or "nothing")
def test_no_bad_option_reaches_the_user_as_a_traceback(tmp_path, args):
    repo = Path(__file__).parents[1]
    args = [str(repo / a) if a.startswith("party/data") else a for a in args]
    status, out, err = party(*args, cwd=tmp_path, timeout=120)
    assert status in (1, 2), (status, err)
    assert "Traceback" not in out + err
    assert not (tmp_path / "o").exists()
    last = err.strip().splitlines()[-1]
    assert last.startswith("error: ") or last.startswith("Error: ") or "Usage:" in err, err
