"""The hostile-input campaign of ``../shared/research/bad-input-campaign.md``, run again.

    python benchmarks/bad_input_campaign.py [--out DIR] [--only ID ...]

Makes the campaign's inputs (its own scripts ``../shared/research/bad-input/mk.py`` and
``mkbody.py``, and the inputs it made inline, remade here), runs its 163 cases in order with the
same commands, each under a 300 s timeout and a 6 GB memory watchdog, and prints a table: exit
status, the last line printed, whether a traceback appeared, the peak resident memory, and a
verdict: ``clear error`` (exit 1 with one ``error:`` line), ``result`` (exit 0; with the check
the case needs, e.g. the user's files intact, frames equal to an uninterrupted run's), or what
went wrong (``traceback``, ``memory blow-up``, ``hang``, ``DATA LOSS``, ``wrong result``). The
table is also written to ``DIR/campaign.md``. Judging whether an error line is clear is left to
the reader: the table shows every one.
"""

from __future__ import annotations

import argparse
import filecmp
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

SHARED = Path(__file__).resolve().parents[2] / "shared"
GC = SHARED / "data" / "garmentcode"
BODY = GC / "bodies" / "mean_all.obj"
PATTERNS = GC / "patterns"
TIMEOUT = 300.0
MEMORY_LIMIT = 6.0e9
EXAMPLE_FABRIC = {"areal_density": "0.2", "tensile_warp": "500.0", "tensile_weft": "400.0", "damping": "30.0",
                  "bending_rigidity_kes": "0.05", "shear_kes": "0.8"}


@dataclass
class Outcome:
    status: int | None
    last: str
    traceback: bool
    peak_mb: float
    note: str = ""


@dataclass
class Case:
    id: str
    args: list[str] | None = None
    expect: str = "error"  # "error", "result" or "special"
    check: Callable[["Campaign", Outcome, "Case"], str] | None = None
    cwd: Path | None = None
    env: dict = field(default_factory=dict)
    run: Callable[["Campaign"], Outcome] | None = None


def pattern(name: str) -> str:
    return str(PATTERNS / f"{name}_specification.json")


class Campaign:
    def __init__(self, root: Path) -> None:
        self.root = root
        self.inputs = root / "in"
        self.out = root / "o"

    # -- running -------------------------------------------------------------------------------

    def party(self, args: list[str], *, cwd: Path | None = None, env: dict | None = None,
              interrupt: tuple[int, float] | None = None, wait_for: Path | None = None) -> Outcome:
        """Run ``party ARGS`` under the timeout and the memory watchdog; ``interrupt`` (signal,
        seconds) sends the signal that long after start (or once ``wait_for`` exists)."""
        command = [sys.executable, "-m", "party.cli", *args]
        started = time.monotonic()
        child = subprocess.Popen(command, cwd=cwd or self.root, env={**os.environ, **(env or {})},
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                 preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))  # as a terminal
        peak = [0.0]
        killed = [""]

        def watch() -> None:
            sent = False
            while child.poll() is None:
                rss = _rss(child.pid)
                peak[0] = max(peak[0], rss)
                if rss > MEMORY_LIMIT:
                    killed[0] = "memory"
                    child.kill()
                elif time.monotonic() - started > TIMEOUT:
                    killed[0] = "timeout"
                    child.kill()
                elif interrupt and not sent and time.monotonic() - started > interrupt[1] and (
                        wait_for is None or wait_for.exists()):
                    child.send_signal(interrupt[0])
                    sent = True
                time.sleep(0.1)

        watcher = threading.Thread(target=watch)
        watcher.start()
        out, err = child.communicate()
        watcher.join()
        text = (err.strip() or out.strip()).splitlines()
        last = text[-1] if text else ""
        status = child.returncode
        if killed[0] == "memory":
            last, status = f"watchdog: RSS over {MEMORY_LIMIT / 1e9:g} GB, killed", 137
        elif killed[0] == "timeout":
            last, status = "timeout", 124
        return Outcome(status, last, "Traceback" in out + err, peak[0] / 1e6)

    def judge(self, case: Case, outcome: Outcome) -> str:
        if outcome.traceback:
            return "traceback"
        if outcome.status == 137 and "watchdog" in outcome.last:
            return "memory blow-up"
        if outcome.status == 124:
            return "hang"
        note = case.check(self, outcome, case) if case.check else outcome.note
        if note.startswith(("DATA LOSS", "wrong result")):
            return note
        if case.expect == "error":
            usage = outcome.status == 2 and outcome.last.startswith("Error:")  # click's usage errors
            verdict = "clear error" if (outcome.status == 1 and outcome.last.startswith("error:")) or usage else \
                f"unexpected (exit {outcome.status})"
        elif case.expect == "result":
            verdict = "result" if outcome.status == 0 else f"refused: {outcome.last}"
        else:
            verdict = "handled"
        return verdict + (f": {note}" if note else "")

    # -- inputs --------------------------------------------------------------------------------

    def make_inputs(self) -> None:
        shutil.rmtree(self.root, ignore_errors=True)
        self.inputs.mkdir(parents=True)
        self.out.mkdir()
        env = {**os.environ, "GC": str(GC)}
        for script in ("mk.py", "mkbody.py"):
            subprocess.run([sys.executable, str(SHARED / "research" / "bad-input" / script)], cwd=self.inputs, env=env,
                           check=True, capture_output=True)
        hoody = json.loads(Path(pattern("hoody_mean")).read_text())

        def variant(name: str, change: Callable[[dict], None]) -> None:
            doc = json.loads(json.dumps(hoody))
            change(doc)
            (self.inputs / name).write_text(json.dumps(doc))

        def times_100(doc: dict) -> None:
            for panel in doc["pattern"]["panels"].values():
                panel["translation"] = [100 * t for t in panel["translation"]]

        variant("translation_x100.json", times_100)
        variant("translation_20m.json", lambda d: d["pattern"]["panels"]["left_btorso"].__setitem__(
            "translation", [2000.0, 0.0, 0.0]))

        def sliver(doc: dict) -> None:
            panel = doc["pattern"]["panels"]["left_hood"]
            low, high = min(v[1] for v in panel["vertices"]), max(v[1] for v in panel["vertices"])
            for v in panel["vertices"]:
                v[1] = low + 0.15 * (v[1] - low) / (high - low)  # 1.5 mm high, in cm
            for edge in panel["edges"]:
                edge.pop("curvature", None)
        variant("sliver.json", sliver)
        (self.inputs / "dir.json").mkdir()
        (self.inputs / "party_fmt_empty.json").write_text(json.dumps({"format": "party-pattern"}))
        (self.inputs / "party_fmt_wrong.json").write_text(json.dumps({"format": "party-pattern", "panels": 5}))
        import numpy as np
        import trimesh

        body = trimesh.load(BODY, process=False)
        faces = np.asarray(body.faces)[:: len(body.faces) // 10][:10]
        used, compact = np.unique(faces, return_inverse=True)
        trimesh.Trimesh(np.asarray(body.vertices)[used], compact.reshape(-1, 3), process=False).export(
            self.inputs / "body_10tri_compact.obj")
        (self.inputs / "body_garbage.stl").write_bytes(os.urandom(4000))
        broken = {"negdensity": ("areal_density", "-0.2"), "zerostiff": ("tensile_warp", "0.0"),
                  "string": ("areal_density", "'0.2'"), "nan": ("areal_density", "nan"),
                  "stiff": ("tensile_warp", "5e12")}
        for name, (key, value) in broken.items():
            values = {**EXAMPLE_FABRIC, key: value}
            (self.inputs / f"fab_{name}.toml").write_text("".join(f"{k} = {v}\n" for k, v in values.items()))
        (self.inputs / "fab_unknownkey.toml").write_text(
            "".join(f"{k} = {v}\n" for k, v in EXAMPLE_FABRIC.items()) + "colour = 'red'\n")
        (self.inputs / "fab_syntax.toml").write_text("areal_density = 0.2\ntensile_warp = 500\ntensile_weft = \n")
        (self.inputs / "fab_badjson.json").write_text('{"areal_density": 0.2, "tensile_warp": 500\n"x": 1}')
        (self.inputs / "fab_list.json").write_text("[0.2, 500, 400, 30]")
        (self.inputs / "fab_section.toml").write_text(
            "[cotton]\n" + "".join(f"{k} = {v}\n" for k, v in EXAMPLE_FABRIC.items()))
        (self.inputs / "fab.yaml").write_text("areal_density: 0.2\n")
        self._dxf()
        (self.inputs / "ro").mkdir()
        subprocess.run(["chattr", "+i", str(self.inputs / "ro")], capture_output=True)
        (self.out / "existing_file.txt").write_text("the user's file\n")

    def _dxf(self) -> None:
        import ezdxf

        def document(units: int | None) -> "ezdxf.document.Drawing":
            doc = ezdxf.new("R2000")
            if units is not None:
                doc.header["$INSUNITS"] = units
            for name, width in (("front", 50), ("back", 50)):
                block = doc.blocks.new(name=name.upper())
                outline = [(0, 0), (width, 0), (width, 70), (0, 70)]
                block.add_polyline2d(outline, close=True, dxfattribs={"layer": "1"})
                block.add_line((width / 2, 5), (width / 2, 65), dxfattribs={"layer": "7"})
                for p in outline:
                    block.add_point(p, dxfattribs={"layer": "2"})
                block.add_text(f"Piece Name: {name}", dxfattribs={"layer": "1"})
                doc.modelspace().add_blockref(name.upper(), (0, 0))
            return doc

        seams = {"seams": [{"a": {"panel": "front", "edge": 1}, "b": {"panel": "back", "edge": 3}},
                           {"a": {"panel": "front", "edge": 3}, "b": {"panel": "back", "edge": 1}}],
                 "parts": {"front": "front", "back": "back"}}
        document(5).saveas(self.inputs / "good.dxf")
        (self.inputs / "good.seams.json").write_text(json.dumps(seams))
        document(None).saveas(self.inputs / "nounits.dxf")
        (self.inputs / "nounits.dxf.seams.json").write_text(json.dumps(seams))
        (self.inputs / "nounits.seams.json").write_text(json.dumps(seams))
        (self.inputs / "garbseams.dxf.seams.json").write_text("{not: json")
        bad = json.loads(json.dumps(seams))
        bad["seams"][0]["a"]["panel"] = "sleeve"
        (self.inputs / "badref.seams.json").write_text(json.dumps(bad))


def _rss(pid: int) -> float:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    return 0.0


def drape(pattern_path: str, out: str, *extra: str, body: str = str(BODY), images: bool = False) -> list[str]:
    return ["drape", pattern_path, "--body", body, "--out", f"o/{out}", "--spacing-mm", "40", "--no-progress",
            *([] if images else ["--no-images"]), *extra]


def cases() -> list[Case]:
    P = lambda name: f"in/{name}"  # noqa: E731
    hoody = pattern("hoody_mean")
    c: list[Case] = []
    for k, (cid, name) in enumerate([
            ("P_notjson", "notjson.json"), ("P_truncated", "truncated.json"), ("P_empty", "empty.json"),
            ("P_list", "list.json"), ("P_emptyobj", "emptyobj.json"), ("P_pattern_int", "pattern_int.json"),
            ("P_panels_list", "panels_list.json"), ("P_panels_empty", "panels_empty.json"),
            ("P_stitch_missing_panel", "stitch_missing_panel.json"), ("P_stitch_missing_edge", "stitch_missing_edge.json"),
            ("P_stitch_neg_edge", "stitch_neg_edge.json"), ("P_stitch_str_edge", "stitch_str_edge.json"),
            ("P_stitch_self", "stitch_self.json"), ("P_zero_area", "zero_area.json"),
            ("P_self_intersect", "self_intersect.json"), ("P_dup_vertex", "dup_vertex.json"), ("P_nan", "nan.json"),
            ("P_huge", "huge.json"), ("P_inf_translation", "inf_translation.json"),
            ("P_units_x100_big", "units_x100_big.json"), ("P_units_x100_small", "units_x100_small.json"),
            ("P_no_properties", "no_properties.json"), ("P_units_zero", "units_zero.json"),
            ("P_rot_string_json", "rot_string.json"), ("P_edge_bad_endpoint_json", "edge_bad_endpoint.json"),
            ("P_wild_curvature_json", "wild_curvature.json"), ("P_far_translation_json", "far_translation.json"),
            ("P_utf16_json", "utf16.json"), ("P_bom_json", "bom.json"), ("P_pattern_txt", "pattern.txt"),
            ("P_garbage_dxf", "garbage.dxf"), ("P_text_dxf", "text.dxf"),
            ("P_translation_x100", "translation_x100.json"), ("P_translation_20m", "translation_20m.json"),
            ("P_directory", ""), ("P_directory_json", "dir.json"), ("P_missing", "nosuch.json")]):
        expect = "result" if cid in ("P_stitch_str_edge", "P_bom_json") else "error"
        c.append(Case(cid, drape(P(name).rstrip("/"), cid), expect, check=_quality if expect == "result" else None))
    for cid, body, extra in [
            ("B_body_open", "body_open.obj", []), ("B_body_flipped", "body_flipped.obj", []),
            ("B_body_10tri_obj", "body_10tri.obj", []), ("B_body_10tri_compact_obj", "body_10tri_compact.obj", []),
            ("B_body_huge_obj", "body_huge.obj", []), ("B_body_mm_obj", "body_mm.obj", []),
            ("B_body_nan_obj", "body_nan.obj", []), ("B_body_flat_obj", "body_flat.obj", []),
            ("B_body_empty_obj", "body_empty.obj", []), ("B_body_garbage_obj", "body_garbage.obj", []),
            ("B_body_points_ply", "body_points.ply", []), ("B_body_xyz", "body.xyz", []),
            ("B_huge_units_m", "body_huge.obj", ["--units", "m"]),
            ("B_huge_bodyunits_m", "body_huge.obj", ["--body-units", "m"])]:
        expect = "result" if cid == "B_body_mm_obj" else "error"
        c.append(Case(cid, drape(hoody, cid, *extra, body=P(body)), expect, check=_quality if expect == "result" else None))
    for cid, fabric in [("F_fab_negdensity", "fab_negdensity.toml"), ("F_fab_zerostiff", "fab_zerostiff.toml"),
                        ("F_fab_string", "fab_string.toml"), ("F_fab_unknownkey", "fab_unknownkey.toml"),
                        ("F_fab_syntax", "fab_syntax.toml"), ("F_fab_nan", "fab_nan.toml"),
                        ("F_fab_stiff", "fab_stiff.toml"), ("F_fab_badjson", "fab_badjson.json"),
                        ("F_fab_list", "fab_list.json"), ("F_fab_section", "fab_section.toml"), ("F_fab", "fab.yaml"),
                        ("F_nosuchfabric", "nosuchfabric")]:
        c.append(Case(cid, drape(hoody, cid, "--fabric", P(fabric) if fabric != "nosuchfabric" else fabric)))
    js = pattern("js_mean_all")
    for cid, value in [("O_spacing_0", "0"), ("O_spacing_-1", "-1"), ("O_spacing_nan", "nan"), ("O_spacing_inf", "inf"),
                       ("O_spacing_abc", "abc"), ("O_spacing_1e6", "1e6")]:
        args = drape(hoody, cid)
        args[args.index("--spacing-mm") + 1] = value
        c.append(Case(cid, args))
    c.append(Case("O_spacing_0.5_js", ["drape", js, "--body", str(BODY), "--out", "o/O_spacing_05", "--spacing-mm",
                                        "0.5", "--no-progress", "--no-images"]))
    c.append(Case("O_spacing_1_js", ["drape", js, "--body", str(BODY), "--out", "o/O_spacing_1", "--spacing-mm", "1",
                                      "--no-images"]))
    c.append(Case("O_out_file", ["drape", hoody, "--body", str(BODY), "--out", "o/existing_file.txt", "--spacing-mm",
                                 "40", "--no-progress", "--no-images"], check=_file_intact))
    c.append(Case("O_out_readonly", ["drape", hoody, "--body", str(BODY), "--out", "in/ro", "--spacing-mm", "40",
                                     "--no-progress", "--no-images"]))
    c.append(Case("O_out_readonly_sub", ["drape", hoody, "--body", str(BODY), "--out", "in/ro/sub", "--spacing-mm", "40",
                                         "--no-progress", "--no-images"]))
    c.append(Case("O_out_unicode", ["drape", hoody, "--body", str(BODY), "--out", "o/my dräpe ✂ 裙子", "--spacing-mm",
                                    "40", "--no-progress"], "result", check=_quality))
    c.append(Case("O_device_cuda", drape(hoody, "O_device_cuda", "--device", "cuda")))
    c.append(Case("O_device_foo", drape(hoody, "O_device_foo", "--device", "tpu")))
    c.append(Case("R_device_cuda", ["run", "sphere-drop", "--quick", "--out", "o/R_device_cuda", "--device", "cuda",
                                    "--no-progress"]))
    c.append(Case("O_solver_foo", drape(hoody, "O_solver_foo", "--solver", "rk4")))
    c.append(Case("O_up_w", drape(hoody, "O_up_w", "--up", "w")))
    c.append(Case("O_bodyunits_furlong", drape(hoody, "O_bu", "--body-units", "furlong")))
    c.append(Case("O_body_XL", drape(hoody, "O_body_XL", body="XL")))
    c.append(Case("O_body_dir", drape(hoody, "O_body_dir", body="in")))
    c.append(Case("O_body_missing", drape(hoody, "O_body_missing", body="in/nosuch.obj")))
    R = lambda cid, *extra: ["run", *extra, "--out", f"o/{cid}", "--no-progress"]  # noqa: E731
    c.append(Case("R_nosuch", ["run", "nosuch", "--out", "o/R_nosuch"]))
    for cid, extra, expect in [
            ("R_dt1_explicit", ["sphere-drop", "--quick", "--solver", "explicit", "--dt", "1"], "error"),
            ("R_dt1_implicit", ["sphere-drop", "--quick", "--dt", "1"], "error"),
            ("R_dt0.2_implicit", ["sphere-drop", "--quick", "--dt", "0.2"], "error"),
            ("R_dt_explicit_edge", ["sphere-drop", "--quick", "--solver", "explicit", "--dt", "0.00047", "--duration",
                                    "0.2"], "error"),
            ("R_duration_-1", ["sphere-drop", "--quick", "--duration", "-1"], "error"),
            ("R_duration_0", ["sphere-drop", "--quick", "--duration", "0"], "error"),
            ("R_duration_nan", ["sphere-drop", "--quick", "--duration", "nan"], "error"),
            ("R_duration_inf", ["sphere-drop", "--quick", "--duration", "inf"], "error"),
            ("R_grid_0", ["sphere-drop", "--quick", "--grid", "0"], "error"),
            ("R_grid_1", ["sphere-drop", "--quick", "--grid", "1"], "error"),
            ("R_grid_-5", ["sphere-drop", "--quick", "--grid", "-5"], "error"),
            ("R_grid_100000", ["sphere-drop", "--quick", "--grid", "100000"], "error"),
            ("R_spacing_0", ["rod-wind", "--quick", "--spacing", "0"], "error"),
            ("R_wind_on_sphere", ["sphere-drop", "--quick", "--wind", "5"], "error"),
            ("R_selfcoll_maybe", ["sphere-drop", "--quick", "--self-collision", "maybe"], "error"),
            ("R_grid_100000_noquick", ["sphere-drop", "--grid", "100000", "--duration", "0.05"], "error"),
            ("R_rod_spacing_0", ["rod-wind", "--spacing", "0", "--duration", "0.01"], "error"),
            ("R_rod_wind_nan", ["rod-wind", "--wind", "nan", "--duration", "0.01"], "error")]:
        c.append(Case(cid, R(cid, *extra), expect))
    c.append(Case("R_stale_frames", None, "special", run=_stale_frames))
    c.append(Case("R_out_file", ["run", "sphere-drop", "--quick", "--out", "o/existing_file.txt", "--no-progress"],
                  check=_file_intact))
    c.append(Case("R_out_readonly", ["run", "sphere-drop", "--quick", "--out", "in/ro", "--no-progress"]))
    c.append(Case("V_case_nosuch", ["validate", "--case", "nosuch", "--out", "o/V_nosuch"]))
    c.append(Case("V_fabric_neg", ["validate", "--case", "oscillation", "--quick", "--fabric", "in/fab_negdensity.toml",
                                   "--out", "o/V_fabneg"]))
    c.append(Case("V_solver_bad", ["validate", "--case", "oscillation", "--quick", "--solver", "verlet", "--out",
                                   "o/V_solver"]))
    c.append(Case("V_out_file", ["validate", "--case", "oscillation", "--quick", "--out", "o/existing_file.txt"],
                  check=_file_intact))
    c.append(Case("V_resume_corrupt", None, "special", run=lambda k: _validate_resume(k, "V_osc_corrupt", '{"cases": [')))
    c.append(Case("V_resume_wrongshape", None, "special", run=lambda k: _validate_resume(k, "V_osc_wrong", "[1, 2]")))
    c.append(Case("R_sigint", None, "special", run=lambda k: _interrupted_run(k, "R_int", signal.SIGINT)))
    c.append(Case("R_sigint_resume", None, "special", run=lambda k: _resumed_run(k, "R_int")))
    c.append(Case("R_kill9", None, "special", run=lambda k: _interrupted_run(k, "R_k9", signal.SIGKILL)))
    c.append(Case("R_kill9_resume", None, "special", run=lambda k: _resumed_run(k, "R_k9")))
    c.append(Case("D_sigint", None, "special", run=lambda k: _interrupted_drape(k, "D_int", signal.SIGINT)))
    c.append(Case("D_sigint_resume", None, "special", run=lambda k: _resumed_drape(k, "D_int")))
    c.append(Case("D_kill9", None, "special", run=lambda k: _interrupted_drape(k, "D_k9", signal.SIGKILL)))
    c.append(Case("D_kill9_resume", None, "special", run=lambda k: _resumed_drape(k, "D_k9")))
    c.append(Case("D_resume_other_pattern", None, "special", run=_drape_other_pattern))
    c.append(Case("D_resume_truncated", None, "special", run=lambda k: _drape_damaged_checkpoint(k, "D_truncckpt", True)))
    c.append(Case("D_resume_garbage", None, "special", run=lambda k: _drape_damaged_checkpoint(k, "D_garbckpt", False)))
    for cid, folder, extra in [
            ("R_resume_truncated", "R_mid", ["sphere-drop", "--grid", "48", "--duration", "1.5"]),
            ("R_resume_other_grid", "R_mid2", ["sphere-drop", "--grid", "40", "--duration", "1.5"]),
            ("R_resume_other_scene", "R_mid3", ["rod-wind", "--duration", "0.05"]),
            ("R_resume_other_fabric", "R_mid4", ["sphere-drop", "--grid", "48", "--duration", "1.5", "--fabric", "silk"]),
            ("R_resume_other_selfcollision", "R_mid5", ["sphere-drop", "--grid", "48", "--duration", "1.5",
                                                        "--self-collision", "off"]),
            ("R_resume_other_solver", "R_mid6", ["sphere-drop", "--grid", "48", "--duration", "1.5", "--solver",
                                                 "explicit"])]:
        c.append(Case(cid, None, "special", run=lambda k, f=folder, e=extra, cid=cid: _resume_other(k, f, e, cid)))
    for name, images in [("hoody_mean", True), ("tshirt_mean", True), ("dress_pencil", False), ("shirt_mean", False),
                         ("dress_sleeves_flare", False), ("js_mean_all", False)]:
        cid = f"U_{name}_upx"
        c.append(Case(cid, drape(pattern(name), cid, "--up", "x", images=images), "special",
                      check=_refused_or_flagged))
    c.append(Case("X_dxf_nounits", drape("in/nounits.dxf", "X_dxf_nounits", "--seams", "in/good.seams.json")))
    c.append(Case("X_dxf_garbage_seams", drape("in/good.dxf", "X_dxf_gs", "--seams", "in/garbseams.dxf.seams.json")))
    c.append(Case("X_dxf_badref_seams", drape("in/good.dxf", "X_dxf_br", "--seams", "in/badref.seams.json")))
    c.append(Case("X_dxf_missing_seams", drape("in/good.dxf", "X_dxf_ms", "--seams", "in/nosuch.seams.json")))
    for value in ("0", "abc", "-1"):
        c.append(Case(f"E_threads_{value}", ["run", "sphere-drop", "--quick", "--out", f"o/E_threads_{value}",
                                             "--no-progress"], env={"PARTY_THREADS": value}))
    c.append(Case("P_party_fmt_empty", drape("in/party_fmt_empty.json", "P_pfe")))
    c.append(Case("P_party_fmt_wrong", drape("in/party_fmt_wrong.json", "P_pfw")))
    c.append(Case("P_sliver", drape("in/sliver.json", "P_sliver"), "special", check=_refused_or_flagged))
    c.append(Case("B_garbage_stl", drape(hoody, "B_gstl", body="in/body_garbage.stl")))
    c.append(Case("O_units_mm_on_json", drape(hoody, "O_units_json", "--units", "mm", "--seams", "in/badref.seams.json")))
    c.append(Case("D_sigint_over_old", None, "special", run=_sigint_over_old))
    c.append(Case("R_rod_wind_1e4", ["run", "rod-wind", "--wind", "10000", "--duration", "0.05", "--out", "o/R_wind_big",
                                     "--no-progress"]))
    c.append(Case("O_out_empty", None, "special", run=lambda k: _out_in_users_cwd(k, "")))
    c.append(Case("O_out_dot", None, "special", run=lambda k: _out_in_users_cwd(k, ".")))
    c.append(Case("O_out_userfolder", None, "special",
                  run=lambda k: _users_folder(k, "userfolder", drape(hoody, "userfolder"))))
    c.append(Case("R_out_userfolder", None, "special",
                  run=lambda k: _users_folder(k, "userfolder2", ["run", "sphere-drop", "--quick", "--out",
                                                                 "o/userfolder2", "--no-progress"])))
    c.append(Case("V_out_userfolder", None, "special",
                  run=lambda k: _users_folder(k, "userfolder3", ["validate", "--case", "oscillation", "--quick", "--out",
                                                                 "o/userfolder3"])))
    c.append(Case("R_dress_sigint", None, "special", run=_dress_sigint))
    c.append(Case("R_dress_resume_trunc_sewn", None, "special", run=_dress_truncated_sewing))
    for cid, value in [("R_dt_0", "0"), ("R_dt_-1", "-1"), ("R_dt_nan", "nan"), ("R_dt_1e-12", "1e-12")]:
        c.append(Case(cid, ["run", "sphere-drop", "--quick", "--dt", value, "--out", f"o/{cid}", "--no-progress"]))
    c.append(Case("D_concurrent_same", None, "special", run=lambda k: _concurrent(
        k, drape(hoody, "D_conc", images=True), drape(hoody, "D_conc", images=True), 3.0)))
    c.append(Case("D_concurrent_diff", None, "special", run=lambda k: _concurrent(
        k, drape(pattern("tshirt_mean"), "D_conc2", images=True), drape(hoody, "D_conc2", images=True), 2.0)))
    c.append(Case("R_concurrent_diff", None, "special", run=lambda k: _concurrent(
        k, R("R_conc", "sphere-drop", "--grid", "48", "--duration", "1.5"),
        R("R_conc", "sphere-drop", "--grid", "48", "--duration", "1.0", "--fabric", "silk"), 1.0)))
    return c


# -- checks and special cases ------------------------------------------------------------------

def _out_folder(k: Campaign, case: Case) -> Path:
    return k.root / case.args[case.args.index("--out") + 1]


def _quality(k: Campaign, outcome: Outcome, case: Case) -> str:
    path = _out_folder(k, case) / "summary.json"
    if outcome.status != 0 or not path.exists():
        return ""
    quality = json.loads(path.read_text()).get("quality", {})
    return "gates passed" if quality.get("passed") else f"gates failed: {'; '.join(quality.get('reasons', []))}"


def _refused_or_flagged(k: Campaign, outcome: Outcome, case: Case) -> str:
    """An input no worn garment comes of (the wrong up axis, a 1.5 mm panel): refused, or draped
    with its gates failed and said in a warning line; passing its gates would be a wrong result."""
    if outcome.status == 1:
        return "refused: " + outcome.last.removeprefix("error: ")
    summary = json.loads((_out_folder(k, case) / "summary.json").read_text())
    if not summary["quality"]["passed"] and "warning: the drape missed its quality gates" in outcome.last:
        return "gate failed with a warning line: " + "; ".join(summary["quality"]["reasons"])
    return "wrong result: passed its gates"


def _file_intact(k: Campaign, outcome: Outcome, case: Case) -> str:
    return "" if (k.out / "existing_file.txt").read_text() == "the user's file\n" else "DATA LOSS: the file changed"


def _stale_frames(k: Campaign) -> Outcome:
    k.party(["run", "sphere-drop", "--quick", "--out", "o/R_stale", "--no-progress"])
    outcome = k.party(["run", "sphere-drop", "--quick", "--duration", "0.1", "--out", "o/R_stale", "--no-progress"])
    frames = len(list((k.out / "R_stale" / "frames").glob("frame_*.ply")))
    summary = json.loads((k.out / "R_stale" / "summary.json").read_text())
    outcome.note = "result: stale frames removed" if frames == summary["frames"] else "wrong result: stale frames kept"
    return outcome


def _validate_resume(k: Campaign, folder: str, content: str) -> Outcome:
    k.party(["validate", "--case", "oscillation", "--quick", "--out", f"o/{folder}"])
    (k.out / folder / "results.json").write_text(content)
    outcome = k.party(["validate", "--case", "oscillation", "--quick", "--resume", "--out", f"o/{folder}"])
    outcome.note = "result with a warning" if outcome.status == 0 else ""
    return outcome


RUN_48 = ["run", "sphere-drop", "--grid", "48", "--duration", "1.5", "--no-progress"]


def _reference_run(k: Campaign) -> Path:
    reference = k.out / "R_full"
    if not (reference / "summary.json").exists():
        k.party(RUN_48 + ["--out", "o/R_full"])
    return reference


def _interrupted_run(k: Campaign, folder: str, sig: int) -> Outcome:
    """The 48 x 48 drop stopped by ``sig`` once it has written its 20th of 45 frames."""
    _reference_run(k)
    outcome = k.party(RUN_48 + ["--out", f"o/{folder}"], interrupt=(sig, 0.0),
                      wait_for=k.out / folder / "frames" / "frame_000020.ply")
    outcome.note = _stopped(outcome, sig) + ("checkpoint kept" if (k.out / folder / "checkpoint.npz").exists()
                                             else "no checkpoint")
    return outcome


def _stopped(outcome: Outcome, sig: int) -> str:
    """What a run sent ``sig`` did: stopped as it should, or finished first (the case then
    tests nothing)."""
    expected = 130 if sig == signal.SIGINT else -sig
    return "" if outcome.status == expected else f"not stopped by the signal (exit {outcome.status}); "


def _resumed_run(k: Campaign, folder: str) -> Outcome:
    outcome = k.party(RUN_48 + ["--out", f"o/{folder}", "--resume"])
    frames = sorted((k.out / "R_full" / "frames").glob("frame_*.ply"))
    differ = [f.name for f in frames if not filecmp.cmp(f, k.out / folder / "frames" / f.name, shallow=False)]
    outcome.note = ("result: every frame identical to the uninterrupted run's" if not differ else
                    f"wrong result: {len(differ)} frames differ from the uninterrupted run's")
    return outcome


def _reference_drape(k: Campaign) -> Path:
    reference = k.out / "base_hoody"
    if not (reference / "summary.json").exists():
        k.party(["drape", pattern("hoody_mean"), "--body", str(BODY), "--out", "o/base_hoody", "--spacing-mm", "40",
                 "--no-progress"])
    return reference


def _interrupted_drape(k: Campaign, folder: str, sig: int) -> Outcome:
    """The hoody's drape stopped by ``sig`` once its sewing has saved a checkpoint."""
    _reference_drape(k)
    outcome = k.party(["drape", pattern("hoody_mean"), "--body", str(BODY), "--out", f"o/{folder}", "--spacing-mm", "40",
                       "--no-progress"], interrupt=(sig, 0.0), wait_for=k.out / folder / "checkpoint.npz")
    strays = [p.name for p in k.out.iterdir() if p.name.startswith(f".{folder}.")]
    outcome.note = _stopped(outcome, sig) + ("no stray staging folder" if not strays else f"stray staging folders {strays}")
    return outcome


def _resumed_drape(k: Campaign, folder: str) -> Outcome:
    outcome = k.party(["drape", pattern("hoody_mean"), "--body", str(BODY), "--out", f"o/{folder}", "--spacing-mm", "40",
                       "--no-progress", "--resume"])
    same = filecmp.cmp(k.out / "base_hoody" / "garment.obj", k.out / folder / "garment.obj", shallow=False)
    staging = [p.name for p in (k.out / folder).iterdir() if p.name.startswith(".party-staging")]
    outcome.note = ("garment identical to the uninterrupted drape's" if same else "garment differs from the "
                    "uninterrupted drape's (a drape resumed while draping takes another path to rest)") + \
        ("" if not staging else f"; stray staging {staging}")
    return outcome


def _drape_other_pattern(k: Campaign) -> Outcome:
    k.party(drape(pattern("hoody_mean"), "D_wrongckpt"), interrupt=(signal.SIGKILL, 0.0),
            wait_for=k.out / "D_wrongckpt" / "checkpoint.npz")
    return k.party(drape(pattern("tshirt_mean"), "D_wrongckpt", "--resume"))


def _drape_damaged_checkpoint(k: Campaign, folder: str, truncate: bool) -> Outcome:
    k.party(drape(pattern("hoody_mean"), folder), interrupt=(signal.SIGKILL, 0.0),
            wait_for=k.out / folder / "checkpoint.npz")
    path = k.out / folder / "checkpoint.npz"
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2] if truncate else os.urandom(5000))
    return k.party(drape(pattern("hoody_mean"), folder, "--resume"))


def _resume_other(k: Campaign, folder: str, extra: list[str], cid: str) -> Outcome:
    k.party(RUN_48 + ["--out", f"o/{folder}"], interrupt=(signal.SIGINT, 0.0),
            wait_for=k.out / folder / "frames" / "frame_000005.ply")
    if cid == "R_resume_truncated":
        path = k.out / folder / "checkpoint.npz"
        path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    return k.party(["run", *extra, "--out", f"o/{folder}", "--no-progress", "--resume"])


def _sigint_over_old(k: Campaign) -> Outcome:
    k.party(["drape", pattern("hoody_mean"), "--body", str(BODY), "--out", "o/keep", "--spacing-mm", "40",
             "--no-progress"])
    before = (k.out / "keep" / "garment.obj").read_bytes()
    outcome = k.party(["drape", pattern("tshirt_mean"), "--body", str(BODY), "--out", "o/keep", "--spacing-mm", "40",
                       "--no-progress"], interrupt=(signal.SIGINT, 0.0), wait_for=k.out / "keep" / "checkpoint.npz")
    outcome.note = _stopped(outcome, signal.SIGINT) + (
        "old results intact" if (k.out / "keep" / "garment.obj").read_bytes() == before else "DATA LOSS: old results replaced")
    return outcome


def _users_files(folder: Path) -> None:
    (folder / "photos").mkdir(parents=True)
    (folder / "thesis.tex").write_text("my thesis\n")
    (folder / "photos" / "a.jpg").write_bytes(b"jpeg")


def _intact(folder: Path) -> bool:
    return ((folder / "thesis.tex").exists() and (folder / "thesis.tex").read_text() == "my thesis\n"
            and (folder / "photos" / "a.jpg").exists())


def _out_in_users_cwd(k: Campaign, out: str) -> Outcome:
    cwd = k.root / f"user_cwd_{out or 'empty'}"
    _users_files(cwd)
    (cwd / "notes.txt").write_text("notes\n")
    outcome = k.party(["drape", pattern("hoody_mean"), "--body", str(BODY), "--out", out, "--spacing-mm", "40",
                       "--no-progress", "--no-images"], cwd=cwd)
    outcome.note = "user's files intact" if _intact(cwd) and (cwd / "notes.txt").exists() else "DATA LOSS"
    return outcome


def _users_folder(k: Campaign, folder: str, args: list[str]) -> Outcome:
    _users_files(k.out / folder)
    outcome = k.party(args)
    outcome.note = "user's files intact" if _intact(k.out / folder) else "DATA LOSS"
    return outcome


def _dress_sigint(k: Campaign) -> Outcome:
    outcome = k.party(["run", "dress", "--quick", "--out", "o/R_dress", "--no-progress"],
                      interrupt=(signal.SIGINT, 0.0), wait_for=k.out / "R_dress" / "checkpoint.npz")
    kept = [p for p in ("sewn.npz", "checkpoint.npz") if (k.out / "R_dress" / p).exists()]
    outcome.note = _stopped(outcome, signal.SIGINT) + (f"kept {', '.join(kept)}" if kept else "nothing kept")
    return outcome


def _dress_truncated_sewing(k: Campaign) -> Outcome:
    path = k.out / "R_dress" / "sewn.npz"
    if path.exists():
        path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    return k.party(["run", "dress", "--quick", "--out", "o/R_dress", "--no-progress", "--resume"])


def _concurrent(k: Campaign, first: list[str], second: list[str], delay: float) -> Outcome:
    results: list[Outcome] = []
    thread = threading.Thread(target=lambda: results.append(k.party(first)))
    thread.start()
    time.sleep(delay)
    later = k.party(second)
    thread.join()
    earlier = results[0]
    refused = later.status == 1 and "is in use by another party run" in later.last
    later.note = (f"first: exit {earlier.status}; second refused naming the first" if refused and earlier.status == 0
                  else f"wrong result: first exit {earlier.status}, second exit {later.status}")
    return later


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out/bad_input_campaign"))
    parser.add_argument("--only", nargs="*", help="case ids to run (default: all)")
    args = parser.parse_args()
    campaign = Campaign(args.out.resolve())
    campaign.make_inputs()
    rows = []
    counts: dict[str, int] = {}
    chosen = [c for c in cases() if not args.only or c.id in args.only]
    try:
        for number, case in enumerate(chosen, 1):
            if case.run is not None:
                outcome = case.run(campaign)
            else:
                outcome = campaign.party(case.args, cwd=case.cwd, env=case.env)
            verdict = campaign.judge(case, outcome)
            kind = verdict.split(":")[0]
            counts[kind] = counts.get(kind, 0) + 1
            row = (f"| {number} | {case.id} | {outcome.status} | {outcome.last.replace('|', '/')} | "
                   f"{'yes' if outcome.traceback else 'no'} | {outcome.peak_mb:.0f} | {verdict} |")
            rows.append(row)
            print(row, flush=True)
    finally:
        subprocess.run(["chattr", "-i", str(campaign.inputs / "ro")], capture_output=True)
    summary = ", ".join(f"{n} {kind}" for kind, n in sorted(counts.items(), key=lambda item: -item[1]))
    print(f"\n{len(rows)} cases: {summary}")
    (campaign.root / "campaign.md").write_text(
        "| # | id | exit | last line | traceback | peak MB | verdict |\n|---|---|---|---|---|---|---|\n"
        + "\n".join(rows) + f"\n\n{len(rows)} cases: {summary}\n")


if __name__ == "__main__":
    main()
