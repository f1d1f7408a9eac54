"""party against Blender and Newton, measured in one run.

    python benchmarks/compare.py [--grids 64 100] [--self-collision off on]
                                 [--systems party-implicit party-implicit-150hz party-explicit blender newton]
                                 [--seconds 1] [--repeats 1] [--garments/--no-garments] [--flare-spacing-mm 20 9]
                                 [--out benchmarks/results] [--resume]

Scene (a), sphere drop: a 1 m cloth of N x N nodes falls 0.32 m onto a sphere of radius 0.3 m for 1
s, or ``--seconds`` (``party run sphere-drop``; ``benchmarks/peers/`` for the peers), every system
in the scene's fabric (the peers are handed it, :func:`sphere_fabric_json`, and set their own models
from it). Each peer runs in its own virtual environment under ``benchmarks/.venvs/``, made here if
missing (bpy 5.0.1 needs Python 3.11; newton 1.8.0). Printed per scene and system: wall seconds per
simulated second with start-up (imports, set-up, the first frame's kernel compilation) excluded and
reported apart, the ratio to party's implicit solver, and the outcome checked the same way for all
(smallest distance of a node from the sphere's centre, nodes inside the sphere, cloth crossings:
mesh edges through a triangle of the final mesh, a peer's quads split in two; final height range,
and how far the final shape lies from party implicit's: the mean and the largest distance from a
node of either to the nearest point of the other's surface, the largest being the symmetric
Hausdorff distance between the nodes and the surfaces; a node's nearest node would count the net's
sampling as a difference, up to half a spacing between two nets on one surface; and the stretch
along the grid, the largest and the share of row or column neighbours beyond 5 %; and the nodes'
mean speed over the last :data:`LAST_INTERVAL`, which says how near rest the shapes compared are:
at 1 s the 64x64 sheets still moved at 5 to 60 mm/s on average on 2026-12-06). The outcome is
equal where no node is inside the sphere, no edge crosses the cloth (with self-collision on) and the
shapes lie within :data:`SAME_SHAPE` of each other. ``party-implicit-150hz`` is party's implicit
solver at Blender's step (``--dt``: 30 frames a second at quality 5, 1/150 s, where party's own is
1/300 s). Last lines per scene give party implicit's speed-up over each peer, and Blender's time
over ``party-implicit-150hz``, step for step.

Scenes (b) and (c), party only: the reference dress (``party/data/patterns``) on the default
dress form and GarmentCode's ``dress_sleeves_flare`` on ``mean_all.obj`` (from
``../shared/data/garmentcode``, skipped when absent) sewn and draped to rest, wall seconds
in all, against GarmentCode's own 1,086 s for the flare dress. GarmentCode's mesh of it has
22,336 vertices; party's net at its default 20 mm spacing a fifth as many nodes (4,526), so the
flare dress is also draped at 9 mm, where the net has as many (22,449): the like-for-like figure.

With ``--repeats N`` every run is made N times, the systems taking turns within each round so
that a change in the machine's load falls on all of them alike; the times reported are the
medians, with the fastest and slowest run (this 2-core machine's runs of one setting spread by
up to a fifth either way), and the outcome is the first run's.

party runs on the CPU, as the peers do, also where a GPU is present (``benchmarks/gpu.py``
measures the GPU). Writes ``OUT/compare.csv`` and ``OUT/compare.png`` (a bar chart), and each
run's results as it finishes (``OUT/runs.jsonl``, :mod:`run_log`): ``--resume`` goes on from
there, running only what the log does not hold from the same code (:func:`code_digest`).
"""

from __future__ import annotations

import argparse
import csv
import functools
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
VENVS = HERE / ".venvs"
PEERS = {"blender": (HERE / "peers" / "blender_sphere.py", ["bpy==5.0.1", "numpy<2"]),
         "newton": (HERE / "peers" / "newton_sphere.py", ["newton==1.8.0"])}
SHARED = HERE.parent.parent / "shared" / "data" / "garmentcode"
FLARE = SHARED / "patterns" / "dress_sleeves_flare_specification.json"
GARMENTCODE_SECONDS = 1086.0
"""GarmentCode's own simulator on dress_sleeves_flare on this machine's kind (its README)."""
GARMENTCODE_VERTICES = 22336
"""The vertices of GarmentCode's mesh of dress_sleeves_flare in that run (its README)."""
GARMENT_SPACING_MM = 20.0
"""The reference dress's node spacing [mm] (``party drape``'s default)."""
FLARE_SPACINGS_MM = (GARMENT_SPACING_MM, 9.0)
"""The node spacings [mm] the flare dress is draped at: party's default, and the spacing at which
party's net has as many nodes as GarmentCode's mesh has vertices (22,449 against 22,336)."""
SPHERE_RADIUS = 0.3
SYSTEMS = ["party-implicit", "party-implicit-150hz", "party-explicit", "blender", "newton"]
PARTY_DT = {"party-implicit": None, "party-implicit-150hz": 1.0 / 150.0, "party-explicit": None}
"""party's time step [s] per system (None: the solver's own)."""
SAME_SHAPE = 0.01
"""Largest distance between two systems' final shapes [m] for an equal outcome (issue 4: 1 cm)."""
STRETCHED = 0.05
"""Strain beyond which :func:`grid_stretch` counts a row or column neighbour pair as stretched [-]."""
LAST_INTERVAL = 1.0 / 30.0
"""The time [s] over which each system's final mean speed is taken: the nodes' displacement from
this long before the end (a frame of Blender's 30 fps, two of Newton's 60 fps) over it."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--grids", type=int, nargs="+", default=[64, 100])
    parser.add_argument("--self-collision", nargs="+", choices=["off", "on"], default=["off", "on"])
    parser.add_argument("--systems", nargs="+", default=SYSTEMS, choices=SYSTEMS)
    parser.add_argument("--seconds", type=float, default=1.0,
                        help="simulated seconds of the sphere drop (at 1 s the cloth still slides)")
    parser.add_argument("--repeats", type=int, default=1, help="runs of each system and scene; medians are reported")
    parser.add_argument("--garments", action=argparse.BooleanOptionalAction, default=True)
    parser.add_argument("--flare-spacing-mm", type=float, nargs="+", default=list(FLARE_SPACINGS_MM),
                        help="node spacings [mm] of GarmentCode's flare dress (9: as many nodes as its own mesh)")
    parser.add_argument("--peer-timeout", type=float, default=1200.0, help="seconds before a peer run is stopped")
    parser.add_argument("--out", type=Path, default=HERE / "results")
    parser.add_argument("--resume", action="store_true", help="take the runs OUT/runs.jsonl holds, run the rest")
    args = parser.parse_args()
    if not args.seconds >= 0.1:
        parser.error(f"--seconds must be at least 0.1, got {args.seconds}")
    if args.repeats < 1:
        parser.error(f"--repeats must be at least 1, got {args.repeats}")
    if not all(spacing > 0.0 for spacing in args.flare_spacing_mm):
        parser.error(f"--flare-spacing-mm must be positive, got {args.flare_spacing_mm}")
    args.out.mkdir(parents=True, exist_ok=True)
    from run_log import RunLog

    log = RunLog(args.out, args.resume)
    rows = []
    for grid in args.grids:
        for self_collision in args.self_collision:
            scene = f"sphere-drop {grid}x{grid} self {self_collision}"
            on = self_collision == "on"
            rows += [{**row, "self_collision": on} for row in in_turns(
                scene, args.systems, args.repeats, "wall_per_simulated_second",
                lambda system: run_sphere(system, grid, on, args.seconds, args.peer_timeout), log,
                {"seconds": args.seconds})]
    if args.garments:
        for label, pattern, body, spacing in garment_scenes(args.flare_spacing_mm):
            drapers = [s for s in args.systems if s in ("party-implicit", "party-explicit")]
            rows += in_turns(label, drapers, args.repeats, "wall_seconds_to_rest",
                             lambda system: run_drape(pattern, body, system.split("-")[1], spacing), log, {})
    report(rows, args.out)


def in_turns(scene: str, systems: list[str], repeats: int, key: str, run, log, settings: dict) -> list[dict]:
    """``run(system)`` for each of ``systems`` in turn, ``repeats`` rounds, printing each result
    and keeping it in ``log`` (:class:`run_log.RunLog`, under ``settings``), or taking it from
    there; one row per system for ``scene``, its time ``key`` the median (:func:`median_run`)."""
    runs = {system: [] for system in systems}
    for round_ in range(repeats):
        for system in systems:
            turn = f" (run {round_ + 1} of {repeats})" if repeats > 1 else ""
            made_with = {**settings, "code": code_digest(system)}
            row = log.get(scene, system, round_, made_with)
            print(f"{scene}: {system}{turn}{' (kept from an earlier run)' if row else ''} ...", flush=True)
            if row is None:
                row = run(system)
                if "error" not in row:  # a failed run is run again when resumed
                    log.put(scene, system, round_, made_with, row)
            runs[system].append(row)
            print(f"    {describe(runs[system][-1])}", flush=True)
    return [{"scene": scene, "system": system, **median_run(results, key)} for system, results in runs.items()]


@functools.cache
def code_digest(system: str) -> str:
    """A digest of the code that ``system``'s runs depend on (:func:`run_log.source_digest`):
    party's runs on the package and these benchmarks, a peer's on its script, these benchmarks
    and the fabric it is handed; a run kept by an older ``--resume`` log is made again when it
    changed."""
    from run_log import source_digest

    if system in PEERS:
        return source_digest([HERE / "peers", *HERE.glob("*.py")], sphere_fabric_json())
    return source_digest([HERE.parent / "party", *HERE.glob("*.py")])


def median_run(results: list[dict], key: str) -> dict:
    """The first of a system's runs of one scene, with ``key`` (a time) replaced by the median
    over the runs and the fastest and slowest added (``key_min``, ``key_max``, ``runs``); the
    first error where any run failed."""
    failed = [r for r in results if "error" in r]
    if failed:
        return failed[0]
    times = [r[key] for r in results]
    row = {**results[0], key: float(np.median(times)), f"{key}_min": min(times), f"{key}_max": max(times),
           "runs": len(times)}
    if "ratio_to_garmentcode" in row:
        row["ratio_to_garmentcode"] = GARMENTCODE_SECONDS / row[key]
    return row


def run_sphere(system: str, grid: int, self_collision: bool, seconds: float, timeout: float) -> dict:
    if system.startswith("party"):
        return party_sphere(system.split("-")[1], grid, self_collision, seconds, PARTY_DT[system], "cpu")
    python = ensure_venv(system)
    script, _ = PEERS[system]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "result.npz"
        command = [str(python), str(script)] + (["--"] if system == "blender" else [])
        command += [str(grid), "1" if self_collision else "0", str(out), str(seconds), sphere_fabric_json()]
        started = time.perf_counter()
        try:
            done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return {"error": f"{system} stopped after {timeout:.0f} s"}
        if done.returncode != 0 or not out.exists():
            tail = (done.stderr or done.stdout).strip().splitlines()[-3:]
            return {"error": f"{system} failed: {' / '.join(tail)}"}
        data = np.load(out)
        total = time.perf_counter() - started
        return {"startup_seconds": float(total - data["wall_seconds"]), "wall_per_simulated_second":
                float(data["wall_seconds"] / data["simulated_seconds"]),
                **outcome(data["points"], data["triangles"], data["points_before"], float(data["interval"]))}


def sphere_fabric_json() -> str:
    """The sphere drop's fabric as the peers take it: ``Fabric.to_dict()`` in JSON, SI units."""
    from party.fabric import fabric_by_name
    from party.scenes.sphere_drop import FABRIC

    return json.dumps(fabric_by_name(FABRIC).to_dict())


def party_sphere(solver: str, grid: int, self_collision: bool, seconds: float, dt: float | None,
                 device: str = "cpu") -> dict:
    """party's sphere drop on ``device``: its time per simulated second, the first frame's steps
    (compilation) apart, and its outcome (:func:`outcome`)."""
    import warp as wp

    from party.scenes.sphere_drop import Settings, build

    started = time.perf_counter()
    scene = build(Settings(grid=grid, self_collision=self_collision, solver=solver, duration=seconds, dt=dt),
                  device=device)
    state, scratch = scene.model.state(), scene.model.state()
    control = scene.model.control()
    steps = int(round(scene.duration / scene.dt))
    first = max(int(round(scene.frame_interval / scene.dt)), 1)
    last = min(max(int(round(LAST_INTERVAL / scene.dt)), 1), steps - first)
    for _ in range(first):
        scene.solver.step(state, scratch, control, scene.dt)
        state, scratch = scratch, state
    wp.synchronize()
    startup = time.perf_counter() - started
    t = time.perf_counter()
    reading = 0.0
    for k in range(steps - first):
        if k == steps - first - last:  # the positions for the final speed (their reading not timed)
            read = time.perf_counter()
            before = state.positions()
            reading = time.perf_counter() - read
        scene.solver.step(state, scratch, control, scene.dt)
        state, scratch = scratch, state
    wp.synchronize()
    wall = (time.perf_counter() - t - reading) * steps / (steps - first)
    return {"startup_seconds": startup, "wall_per_simulated_second": wall / scene.duration,
            **outcome(state.positions(), scene.model.triangles, before, last * scene.dt)}


def outcome(points: np.ndarray, triangles: np.ndarray, points_before: np.ndarray, interval: float) -> dict:
    """The final state's outcome, checked alike for every system, from its nodes' ``points`` [m]
    and ``triangles``, and their ``points_before`` [m] ``interval`` [s] earlier (the mean speed
    over it, ``speed_mean_m_s``)."""
    from party.output.metrics import cloth_crossings

    r = np.linalg.norm(points, axis=1)
    nan = bool(np.isnan(points).any())
    speed = float(np.linalg.norm(np.asarray(points) - np.asarray(points_before), axis=1).mean() / interval)
    return {"nodes": int(len(points)), "min_distance_from_centre_m": float(r.min()), "speed_mean_m_s": speed,
            "nodes_inside": int((r < SPHERE_RADIUS).sum()), "z_min_m": float(points[:, 2].min()),
            "z_max_m": float(points[:, 2].max()), "nan": nan, "points": points, "triangles": np.asarray(triangles),
            "cloth_crossings": -1 if nan else cloth_crossings(points, np.asarray(triangles)),
            **grid_stretch(points)}


def grid_stretch(points: np.ndarray) -> dict:
    """How far the final cloth is stretched along its grid: each system's N x N nodes in rows, as
    all three lay them out, every pair of row or column neighbours against the spacing of the
    1 m square. ``stretch_max``: the largest length over rest [-]; ``stretched_share``: the share
    of pairs stretched by over :data:`STRETCHED` (a cap held stretched by friction shows here
    and not in the shape's distance)."""
    n = int(round(np.sqrt(len(points))))
    grid = points.reshape(n, n, 3)
    lengths = np.concatenate([np.linalg.norm(np.diff(grid, axis=0), axis=2).ravel(),
                              np.linalg.norm(np.diff(grid, axis=1), axis=2).ravel()]) * (n - 1)
    return {"stretch_max": float(lengths.max()), "stretched_share": float((lengths > 1.0 + STRETCHED).mean())}


def shape_distance(result: dict, reference: dict) -> tuple[float, float]:
    """Mean and largest distance [m] from each node of either result (its ``points`` and
    ``triangles``) to the nearest point of the other's surface (the largest is the symmetric
    Hausdorff distance between the nodes and the surfaces)."""
    from party.output.metrics import distances_to_surface

    there = distances_to_surface(result["points"], reference["points"], reference["triangles"])
    back = distances_to_surface(reference["points"], result["points"], result["triangles"])
    both = np.concatenate([there, back])
    return float(both.mean()), float(both.max())


def garment_scenes(flare_spacings_mm=FLARE_SPACINGS_MM):
    """Scenes (b) and (c): (label, pattern, body, node spacing [m]) for the reference dress and for
    GarmentCode's flare dress at each of ``flare_spacings_mm`` (skipped where ../shared lacks it)."""
    from party.scenes.dress import pattern_path

    yield f"reference dress on dress form M, {GARMENT_SPACING_MM:g} mm", pattern_path(), "M", GARMENT_SPACING_MM / 1000
    if not FLARE.exists():
        print(f"(skipping the GarmentCode scene: {FLARE} not found)")
        return
    for spacing in flare_spacings_mm:
        yield (f"GarmentCode dress_sleeves_flare on mean_all, {spacing:g} mm", FLARE,
               str(SHARED / "bodies" / "mean_all.obj"), spacing / 1000)


def run_drape(pattern: Path, body: str, solver: str, spacing: float) -> dict:
    """``party drape`` of ``pattern`` on ``body`` in wool flannel at ``spacing`` [m] with ``solver``:
    the outcome and the wall seconds in all (sewing, draping and output), and for GarmentCode's
    flare dress their ratio to GarmentCode's own time."""
    from party.fabric import wool_flannel
    from party.scenes.drape import DrapeSettings, drape

    with tempfile.TemporaryDirectory() as tmp:
        summary = drape(pattern, body, wool_flannel(), Path(tmp) / "drape",
                        DrapeSettings(spacing=spacing, images=False, progress=False, solver=solver, device="cpu"))
    row = {"wall_seconds_to_rest": summary["wall_seconds"], "at_rest": summary["relaxation"]["at_rest"],
           "nodes": summary["nodes"], "draping_steps": summary["relaxation"]["draping_steps"],
           "max_seam_gap_mm": summary["max_seam_gap_mm"], "body_penetrations": summary["body_penetrations"],
           "body_vertices_through_cloth": summary["body_vertices_through_cloth"],
           "cloth_crossings": summary["cloth_crossings"], "max_elongation": summary["max_elongation"],
           "elements_beyond_limit": summary["elements_beyond_limit"]}
    if Path(pattern) == FLARE:
        row["ratio_to_garmentcode"] = GARMENTCODE_SECONDS / summary["wall_seconds"]
    return row


def ensure_venv(peer: str) -> Path:
    """The peer's interpreter, making its venv (``python -m venv`` + pip) on first use."""
    venv = VENVS / peer
    python = venv / "bin" / "python"
    _, requirements = PEERS[peer]
    if not python.exists():
        if peer == "blender" and sys.version_info[:2] != (3, 11):
            raise SystemExit("bpy 5.0.1 needs Python 3.11; run this benchmark with python3.11")
        print(f"    creating {venv} ({' '.join(requirements)}); this downloads several hundred MB once", flush=True)
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        subprocess.run([str(python), "-m", "pip", "install", "-q", *requirements], check=True)
    return python


def seconds_text(row: dict, key: str, digits: int = 2) -> str:
    """A time of ``row``, with the range over its runs where there were several."""
    text = f"{row[key]:.{digits}f}"
    if row.get("runs", 1) > 1:
        text += f" ({row[key + '_min']:.{digits}f}-{row[key + '_max']:.{digits}f})"
    return text


def describe(row: dict) -> str:
    if "error" in row:
        return row["error"]
    if "wall_seconds_to_rest" in row:
        rest = "to rest" if row["at_rest"] else "and still moving"
        return (f"{row['nodes']} nodes, {seconds_text(row, 'wall_seconds_to_rest', 1)} s {rest}, "
                f"seam gap {row['max_seam_gap_mm']:.1f} mm, "
                f"penetrations {row['body_penetrations']} (body vertices through {row['body_vertices_through_cloth']}), "
                f"crossings {row['cloth_crossings']}, elongation {row['max_elongation']:.3f}"
                + (f" ({row['elements_beyond_limit']} elements beyond their limit)"
                   if row.get("elements_beyond_limit") else "")
                + (f", {row['ratio_to_garmentcode']:.1f}x GarmentCode's {GARMENTCODE_SECONDS:,.0f} s for its "
                   f"{GARMENTCODE_VERTICES:,} vertices" if "ratio_to_garmentcode" in row else ""))
    return (f"{seconds_text(row, 'wall_per_simulated_second')} s per simulated s "
            f"(start-up {row['startup_seconds']:.1f} s), "
            f"min r {row['min_distance_from_centre_m']:.4f} m, inside {row['nodes_inside']}, "
            f"crossings {row['cloth_crossings']}, "
            f"z {row['z_min_m']:.3f}..{row['z_max_m']:.3f} m, stretch {row['stretch_max']:.3f} "
            f"({100 * row['stretched_share']:.2f} % over {100 * STRETCHED:.0f} %), "
            f"mean speed {row['speed_mean_m_s']:.3f} m/s at the end")


def report(rows: list[dict], out: Path) -> None:
    from rich.console import Console
    from rich.table import Table

    implicit = {r["scene"]: r for r in rows if r["system"] == "party-implicit" and "points" in r}
    table = Table(title="party vs Blender vs Newton (2-core CPU unless stated)")
    for column in ("scene", "system", "s per sim s", "x party-implicit", "start-up s", "min r m", "inside", "crossings",
                   "z range m", f"stretch max / >{100 * STRETCHED:.0f} %", "mean speed m/s",
                   "shape vs implicit mm (mean/max)", "equal outcome"):
        table.add_column(column)
    for r in rows:
        if "wall_per_simulated_second" in r:
            reference = implicit.get(r["scene"])
            ratio = (r["wall_per_simulated_second"] / reference["wall_per_simulated_second"] if reference
                     else float("nan"))
            r["ratio_to_party_implicit"] = ratio
            shape = equal = ""
            if reference is not None and not (r["nan"] or reference["nan"]):
                mean, largest = shape_distance(r, reference)
                r["shape_mean_m"], r["shape_max_m"] = mean, largest
                crossed = r["self_collision"] and r["cloth_crossings"] != 0
                r["equal_outcome"] = r["nodes_inside"] == 0 and not crossed and largest <= SAME_SHAPE
                shape, equal = f"{1000 * mean:.1f} / {1000 * largest:.1f}", "yes" if r["equal_outcome"] else "no"
            table.add_row(r["scene"], r["system"], seconds_text(r, "wall_per_simulated_second"), f"{ratio:.2f}",
                          f"{r['startup_seconds']:.1f}", f"{r['min_distance_from_centre_m']:.4f}", str(r["nodes_inside"]),
                          str(r["cloth_crossings"]), f"{r['z_min_m']:.3f}..{r['z_max_m']:.3f}",
                          f"{r['stretch_max']:.3f} / {100 * r['stretched_share']:.2f} %",
                          f"{r['speed_mean_m_s']:.3f}", shape, equal)
        else:
            table.add_row(r["scene"], r["system"], describe(r), "", "", "", "", "", "", "", "", "", "")
    Console(width=200).print(table)
    for scene in dict.fromkeys(r["scene"] for r in rows):
        times = {r["system"]: r["wall_per_simulated_second"] for r in rows
                 if r["scene"] == scene and "wall_per_simulated_second" in r}
        peers = [f"{times[peer] / times['party-implicit']:.2f}x faster than {peer.capitalize()}"
                 for peer in ("blender", "newton") if peer in times and "party-implicit" in times]
        if peers:
            print(f"{scene}: party's implicit solver is {', '.join(peers)}")
        if "blender" in times and "party-implicit-150hz" in times:
            print(f"{scene}: at Blender's step (1/150 s) party's implicit solver is "
                  f"{times['blender'] / times['party-implicit-150hz']:.2f}x faster than Blender")
    plain = [{k: v for k, v in r.items() if k not in ("points", "triangles")} for r in rows]
    with open(out / "compare.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=sorted({k for r in plain for k in r}))
        writer.writeheader()
        writer.writerows(plain)
    chart(rows, out / "compare.png")
    print(f"wrote {out / 'compare.csv'} and {out / 'compare.png'}")


def chart(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    timed = [r for r in rows if "wall_per_simulated_second" in r]
    scenes = list(dict.fromkeys(r["scene"] for r in timed))
    systems = list(dict.fromkeys(r["system"] for r in timed))
    fig, ax = plt.subplots(figsize=(max(6, 2.2 * len(scenes)), 4.5))
    width = 0.8 / max(len(systems), 1)
    for k, system in enumerate(systems):
        values = [next((r["wall_per_simulated_second"] for r in timed if r["scene"] == s and r["system"] == system), 0.0)
                  for s in scenes]
        ax.bar(np.arange(len(scenes)) + k * width, values, width, label=system)
    ax.set_xticks(np.arange(len(scenes)) + width * (len(systems) - 1) / 2, scenes, rotation=15, ha="right", fontsize=8)
    ax.set_ylabel("wall seconds per simulated second")
    ax.set_yscale("log")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    sys.path.insert(0, str(HERE.parent))
    main()
