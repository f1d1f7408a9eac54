"""The benchmark's run log: a stopped comparison goes on from the runs it kept."""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from run_log import RunLog, source_digest  # noqa: E402


def test_kept_runs_come_back_with_their_arrays_and_only_for_the_same_settings(tmp_path):
    row = {"wall_per_simulated_second": 1.5, "nodes_inside": 0, "nan": False,
           "points": np.arange(12, dtype=np.float32).reshape(4, 3), "triangles": np.array([[0, 1, 2], [1, 3, 2]])}
    RunLog(tmp_path, resume=False).put("sphere 16", "party-implicit", 0, {"seconds": 1.0}, row)
    RunLog(tmp_path, resume=False).put("sphere 16", "blender", 0, {"seconds": 1.0}, {"error": None, "x": 2})

    log = RunLog(tmp_path, resume=True)
    assert log.get("sphere 16", "blender", 0, {"seconds": 1.0}) == {"error": None, "x": 2}
    assert log.get("sphere 16", "party-implicit", 0, {"seconds": 1.0}) is None  # the second fresh log cleared it

    RunLog(tmp_path, resume=False).put("sphere 16", "party-implicit", 0, {"seconds": 1.0}, row)
    log = RunLog(tmp_path, resume=True)
    kept = log.get("sphere 16", "party-implicit", 0, {"seconds": 1.0})
    assert kept["wall_per_simulated_second"] == 1.5 and kept["nodes_inside"] == 0 and kept["nan"] is False
    assert np.array_equal(kept["points"], row["points"]) and kept["points"].dtype == np.float32
    assert np.array_equal(kept["triangles"], row["triangles"])
    assert log.get("sphere 16", "party-implicit", 0, {"seconds": 2.0}) is None
    assert log.get("sphere 16", "party-implicit", 1, {"seconds": 1.0}) is None


def test_the_source_digest_changes_with_a_file_or_the_extra_text_and_not_with_compiled_caches(tmp_path):
    (tmp_path / "pkg" / "__pycache__").mkdir(parents=True)
    (tmp_path / "pkg" / "solver.py").write_text("DT = 1 / 300\n")
    (tmp_path / "script.py").write_text("print(1)\n")
    paths = [tmp_path / "pkg", tmp_path / "script.py"]
    first = source_digest(paths, "cotton")

    (tmp_path / "pkg" / "__pycache__" / "solver.cpython-311.pyc").write_bytes(b"\x00\x01")
    assert source_digest(paths, "cotton") == first
    assert source_digest(paths, "denim") != first
    (tmp_path / "pkg" / "solver.py").write_text("DT = 1 / 150\n")
    assert source_digest(paths, "cotton") != first
    (tmp_path / "pkg" / "solver.py").write_text("DT = 1 / 300\n")
    assert source_digest(paths, "cotton") == first
    (tmp_path / "pkg" / "solver.py").rename(tmp_path / "pkg" / "step.py")
    assert source_digest(paths, "cotton") != first
