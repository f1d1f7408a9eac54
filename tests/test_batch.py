"""``party batch``: every item recorded as it finishes, poisoned items isolated, a killed batch
resumed to the manifest an uninterrupted one writes, the same results through Ray."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from party.batch.items import plan
from party.batch.report import reason_kind
from party.errors import InvalidInput

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "garmentcode"
TSHIRT = SHARED / "patterns" / "tshirt_mean_specification.json"
BODY = SHARED / "bodies" / "mean_all.obj"
needs_shared = pytest.mark.skipif(not TSHIRT.exists(), reason=f"GarmentCode samples not found at {SHARED}")
STABLE = ("item", "pattern", "body", "fabric", "status", "reasons", "nodes")
"""Manifest columns that do not depend on when or where an item ran."""


def batch(patterns, out: Path, *extra, **popen) -> subprocess.Popen:
    command = [sys.executable, "-m", "party.cli", "batch", *map(str, patterns), "--bodies", str(BODY),
               "--fabrics", "wool_flannel", "--out", str(out), "--spacing-mm", "40", "--workers", "2", *map(str, extra)]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **popen)


def finished(process: subprocess.Popen) -> tuple[int, str, str]:
    out, err = process.communicate(timeout=1800)
    return process.returncode, out, err


def manifest(dataset: Path) -> list[dict]:
    return pq.read_table(dataset / "manifest.parquet").to_pylist()


def stable(rows: list[dict]) -> list[tuple]:
    return [tuple(json.dumps(r[c]) for c in STABLE) for r in rows]


def copies(folder: Path, names: list[str]) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name in names:
        path = folder / f"{name}_specification.json"
        shutil.copy(TSHIRT, path)
        paths.append(path)
    return paths


def malformed(folder: Path) -> Path:
    path = folder / "torn_specification.json"
    path.write_text('{"pattern": {"panels": {"front": ')
    return path


def test_items_are_every_pattern_on_every_body_in_every_fabric_each_once(tmp_path):
    for name in ("a.json", "b.dxf", "notes.txt", "b.seams.json"):
        (tmp_path / name).write_text("{}")
    items = plan([str(tmp_path), str(tmp_path / "a.json"), str(tmp_path / "*.json")], ["M", "/x/mean_all.obj"],
                 ["denim", "silk"])
    assert [i.name for i in items[:4]] == ["a__M__denim", "a__M__silk", "a__mean_all__denim", "a__mean_all__silk"]
    assert {i.pattern.name for i in items} == {"a.json", "b.dxf"}
    assert len(items) == 2 * 2 * 2


def test_two_patterns_that_would_share_a_folder_are_refused_in_one_line(tmp_path):
    for folder in ("x", "y"):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "skirt.json").write_text("{}")
    with pytest.raises(InvalidInput, match=r"two items of the batch would share the folder 'skirt__M__silk'"):
        plan([str(tmp_path / "x"), str(tmp_path / "y")], ["M"], ["silk"])
    with pytest.raises(InvalidInput, match=r"/nothing\*: no pattern file matches$"):
        plan([str(tmp_path / "nothing*")], ["M"], ["silk"])


def test_reasons_of_one_kind_count_together():
    assert (reason_kind("seam a.edge[1]-b.edge[2] left open 3.1 mm by the sewing")
            == reason_kind("seam c.edge[0]-d.edge[5] left open 12 mm by the sewing"))
    assert (reason_kind("stretched to 1.45 times rest (at most 1.3), in panel 'wb_front', since the sewing")
            == "stretched to # times rest (at most #), in panel …, since the sewing")
    assert (reason_kind("3 nodes inside the body, in panel 'skirt_f' and panel 'skirt_b', in the draping")
            == reason_kind("40 nodes inside the body, in panel 'front', in the draping"))


@needs_shared
@pytest.mark.slow
def test_a_batch_goes_on_past_a_malformed_pattern_and_a_killed_drape(tmp_path):
    good = copies(tmp_path / "patterns", ["tee_a", "tee_b", "tee_c", "tee_d", "doomed"])
    patterns = good[:2] + [malformed(tmp_path / "patterns")] + good[2:]
    dataset = tmp_path / "dataset"
    running = batch(patterns, dataset)
    marker = dataset / "doomed__mean_all__wool_flannel" / ".party"
    deadline = time.monotonic() + 900
    while running.poll() is None and time.monotonic() < deadline:
        if marker.exists() and marker.read_text().strip():
            os.kill(json.loads(marker.read_text())["pid"], signal.SIGKILL)  # as the out-of-memory killer would
            break
        time.sleep(0.2)
    status, out, err = finished(running)
    assert status == 0, err
    rows = {r["item"]: r for r in manifest(dataset)}
    assert list(rows) == ["tee_a__mean_all__wool_flannel", "tee_b__mean_all__wool_flannel",
                          "torn__mean_all__wool_flannel", "tee_c__mean_all__wool_flannel",
                          "tee_d__mean_all__wool_flannel", "doomed__mean_all__wool_flannel"]
    assert rows["torn__mean_all__wool_flannel"]["status"] == "error"
    assert "not valid JSON" in rows["torn__mean_all__wool_flannel"]["reasons"][0]
    assert rows["doomed__mean_all__wool_flannel"]["status"] == "error"
    assert rows["doomed__mean_all__wool_flannel"]["reasons"] == ["killed by SIGKILL (out of memory?)"]
    draped = [r for name, r in rows.items() if name.startswith("tee_")]
    assert all(r["status"] in ("passed", "failed") and r["nodes"] > 100 for r in draped)
    assert len({r["nodes"] for r in draped}) == 1  # one pattern, one mesh
    for r in draped:
        summary = json.loads((dataset / r["item"] / "summary.json").read_text())
        assert r["reasons"] == summary["quality"]["reasons"]
        assert (dataset / r["item"] / "images" / "front.png").exists()
    assert (dataset / "contact_sheet.png").stat().st_size > 10_000
    passed = sum(r["status"] == "passed" for r in rows.values())
    assert f"{passed} of 6 items passed" in out
    assert "killed by SIGKILL (out of memory?)" in out


@needs_shared
@pytest.mark.slow
def test_a_batch_killed_and_resumed_writes_the_manifest_of_one_run_through(tmp_path):
    patterns = copies(tmp_path / "patterns", ["tee_a", "tee_b", "tee_c"]) + [malformed(tmp_path / "patterns")]
    through = tmp_path / "through"
    status, _, err = finished(batch(patterns, through, "--no-images"))
    assert status == 0, err

    killed = tmp_path / "killed"
    running = batch(patterns, killed, "--no-images", start_new_session=True)
    deadline = time.monotonic() + 900
    while not (killed / "manifest.parquet").exists() and running.poll() is None and time.monotonic() < deadline:
        time.sleep(0.2)
    os.killpg(running.pid, signal.SIGKILL)  # the batch and every drape it runs
    running.communicate()
    assert 0 < len(manifest(killed)) < 4
    status, out, err = finished(batch(patterns, killed, "--no-images", "--resume"))
    assert status == 0, err
    assert "skipping" in out
    assert stable(manifest(killed)) == stable(manifest(through))
    assert not list(killed.glob("*/.party-staging-*"))


@needs_shared
@pytest.mark.slow
def test_a_batch_on_ray_writes_the_results_of_a_local_one(tmp_path):
    pytest.importorskip("ray", reason="Ray is an optional extra (pip install 'party[ray]')")
    patterns = copies(tmp_path / "patterns", ["tee"]) + [malformed(tmp_path / "patterns")]
    local, on_ray = tmp_path / "local", tmp_path / "ray"
    assert finished(batch(patterns, local, "--no-images"))[0] == 0
    status, _, err = finished(batch(patterns, on_ray, "--no-images", "--ray", "auto"))
    assert status == 0, err
    assert stable(manifest(on_ray)) == stable(manifest(local))
    assert (on_ray / "tee__mean_all__wool_flannel" / "garment.obj").exists()


@pytest.mark.parametrize("option, value, message", [
    ("--bodies", "M,nobody.obj", "error: nobody.obj: body file not found (presets: S, M, L)"),
    ("--fabrics", "silk,velvet", "error: unknown fabric 'velvet'; known: cotton, denim, knit_jersey, silk, wool_flannel, "
                                 "or a .toml/.json file"),
    ("--workers", "0", "error: --workers must be at least 1, got 0"),
    ("--time-limit", "-5", "error: --time-limit must be a positive number of seconds, got -5"),
])
def test_a_batch_refuses_a_bad_body_fabric_or_setting_before_any_item_runs(tmp_path, option, value, message):
    pattern = tmp_path / "skirt.json"
    pattern.write_text("{}")
    out = tmp_path / "dataset"
    command = [sys.executable, "-m", "party.cli", "batch", str(pattern), "--out", str(out), option, value]
    done = subprocess.run(command, capture_output=True, text=True)
    assert done.returncode == 1
    assert done.stderr.strip() == message
    assert not out.exists()
