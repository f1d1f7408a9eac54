"""Running a scene: stepping, frames written as they come, checks, checkpoints, resume.

Output layout of ``run_scene(scene, out)``:

- ``out/frames/frame_NNNNNN.ply``: the cloth at each output frame [m], names in time order;
- ``out/colliders/NAME.ply``: each collider once [m];
- ``out/images/``: ``sequence.png`` (panels through the run) and ``final.png``;
- ``out/summary.json``: counts, timings and checks (see :func:`run_scene`);
- ``out/checkpoint.npz``: the state and the solver's memory after the last frame, to resume from.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Callable

import numpy as np
import warp as wp
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from ..errors import InvalidInput, SimulationUnstable
from ..output import images
from ..output.frames import frame_path, load_checkpoint, save_checkpoint, write_json, write_mesh
from ..output.folder import OutputFolder, open_output
from ..output.metrics import ColliderProbe, cloth_crossings, max_elongation
from ..solvers.explicit.solver import STABLE_SHARE, critical_time_step
from ..solvers.memory import forget, memory, restore
from .scene import Scene

MAX_SPEED = 100.0
"""Node speed [m/s] taken as a blow-up: no garment motion comes near it."""


def run_scene(scene: Scene, out: Path, *, resume: bool = False, progress: bool = True, overwrite: bool = False,
              folder: OutputFolder | None = None, on_frame: Callable[[int], None] | None = None) -> dict:
    """Simulate ``scene``, writing results under ``out`` as they are computed.

    ``out`` is taken as party's output folder (:mod:`party.output.folder`; ``folder``: one the
    caller already holds). Returns the summary (also written to ``out/summary.json``): nodes,
    steps (the scene's duration in whole steps; the last output frame is shorter where the
    duration ends within it), simulated_seconds, wall_seconds, max_elongation (largest length /
    rest length of any warp or weft element at any output frame), body_penetrations (nodes
    inside a collider, summed over output frames), cloth_crossings (crossing edge-triangle
    pairs, summed over output frames), and the scene's parameters. After each frame it writes a
    checkpoint holding the state and the solver's memory (:mod:`party.solvers.memory`) and what
    the run was asked for; ``resume`` goes on from it, bit for bit as the run would have gone
    on, and refuses one of a run asked for otherwise (another scene, parameters, fabric, solver
    or step; the duration may differ). ``on_frame(frame)`` is called after each frame is written.
    Raises :class:`SimulationUnstable` (frames so far kept, summary written with ``"status":
    "unstable"``) if the integration blows up, and :class:`InvalidInput` where the run would
    take longer than :data:`MAX_RUN_SECONDS`.
    """
    if folder is None:
        with open_output(out, "run", overwrite=overwrite, description=scene.name) as held:
            return run_scene(scene, held.path, resume=resume, progress=progress, folder=held, on_frame=on_frame)
    model, dt = scene.model, scene.dt
    out = Path(out)
    critical = critical_time_step(model)
    stable = scene.solver.stable_time_step()
    if dt > stable:
        raise InvalidInput(f"time step {dt:g} s exceeds this net's {scene.solver.name} stability limit {stable:.3g} s; "
                           f"use --dt {_round_down(stable * STABLE_SHARE):g} or a coarser --spacing")
    steps_per_frame = max(int(round(scene.frame_interval / dt)), 1)
    steps_total = max(int(round(scene.duration / dt)), 1)
    frames_total = -(-steps_total // steps_per_frame)  # the last frame shorter where the duration ends within it
    _refuse_endless(steps_total, dt)

    def steps_by(frame: int) -> int:
        return min(frame * steps_per_frame, steps_total)
    faces = model.triangles
    colliders = model.host.colliders
    host = model.host
    limited = model.limited_elements
    rest = host.element_rest_length
    probe = ColliderProbe(colliders, model.device)

    state, scratch = model.state(), model.state()
    control = model.control()
    checkpoint = out / "checkpoint.npz"
    summary_path = out / "summary.json"
    inputs = run_inputs(scene)
    totals = {"max_elongation": 1.0, "body_penetrations": 0, "cloth_crossings": 0, "wall_seconds": 0.0}
    first_frame = 0
    steps_done = 0
    if resume and checkpoint.exists():
        saved = load_checkpoint(checkpoint)
        _check_same_run(checkpoint, saved, inputs, model.node_count)
        restore(state, saved_part(saved, "state"))
        restore(scene.solver, saved_part(saved, "solver"))
        forget(scene.solver)
        first_frame = int(saved["frame"]) + 1
        steps_done = int(round(state.time / dt))  # off this run's frame grid where its duration was another's
        totals.update({k: float(saved[k]) for k in totals})
    else:
        for stale in (out / "frames").glob("frame_*.ply") if (out / "frames").exists() else []:
            stale.unlink()
        for c in colliders:
            write_mesh(out / "colliders" / f"{c.name}.ply", c.vertices, c.faces)
        _record(out, 0, state.positions(), faces, model, probe, limited, rest, totals)
        first_frame = 1

    summary = {
        "scene": scene.name, "status": "running", "nodes": model.node_count, "triangles": model.triangle_count,
        "dt": dt, "critical_dt": critical, "device": model.device,
        **_summary_numbers(totals, first_frame - 1, steps_done, dt),  # a finished run resumed takes no step
        "parameters": scene.parameters, **scene.summary,
    }
    bar = Progress(TextColumn(f"[bold]{scene.name}[/]"), BarColumn(), TextColumn("{task.completed}/{task.total} frames"),
                   TextColumn("t={task.fields[t]:.3f} s"), TimeElapsedColumn(), TimeRemainingColumn(),
                   disable=not progress, transient=False)
    pace = Pace(steps_total - steps_done, dt)
    with bar:
        task = bar.add_task("run", total=frames_total, completed=first_frame - 1, t=state.time)
        for frame in range(first_frame, frames_total + 1):
            start = time.perf_counter()
            try:  # a blow-up, or a step the solver refused (landing): the frames so far stand
                for _ in range(steps_by(frame) - steps_done):
                    if scene.wind is not None:
                        control.wind = scene.wind(state.time)
                    scene.solver.step(state, scratch, control, dt)
                    state, scratch = scratch, state
                    pace.stepped()
                scene.solver.flush(state)
                wp.synchronize_device(model.device)
                totals["wall_seconds"] += time.perf_counter() - start
                points = state.positions()
                speed = np.linalg.norm(state.velocities(), axis=1).max() if model.node_count else 0.0
                if not np.all(np.isfinite(points)) or not speed < MAX_SPEED:
                    kept = "only the first frame is" if frame == 1 else f"frames 0 to {frame - 1} are"
                    raise SimulationUnstable(
                        f"simulation became unstable before t = {state.time:.4f} s (max node speed "
                        f"{speed:.3g} m/s); {kept} kept in {out / 'frames'}; "
                        f"try a smaller --dt, e.g. {_round_down(dt / 2):g}")
            except SimulationUnstable:
                summary.update(_summary_numbers(totals, frame - 1, steps_done, dt), status="unstable")
                write_json(summary_path, summary)
                raise
            _record(out, frame, points, faces, model, probe, limited, rest, totals)
            save_checkpoint(checkpoint, inputs=json.dumps(inputs, sort_keys=True), frame=frame, time=state.time,
                            **{k: v for k, v in totals.items()}, **memory_of(state, "state"),
                            **memory_of(scene.solver, "solver"))
            steps_done = steps_by(frame)
            summary.update(_summary_numbers(totals, frame, steps_done, dt))
            write_json(summary_path, summary)
            bar.update(task, completed=frame, t=state.time)
            if on_frame is not None:
                on_frame(frame)

    summary["status"] = "finished"
    write_json(summary_path, summary)
    times = [steps_by(k) * dt for k in range(frames_total + 1)]
    if scene.pictures is not None:
        scene.pictures(out, [(t, frame_path(out, k)) for k, t in enumerate(times)])
    else:
        _pictures(out, scene, times, faces, colliders)
    return summary


def run_inputs(scene: Scene) -> dict:
    """What a run was asked for, as its checkpoint records it: the scene, its parameters but
    the duration (a resumed run may go on longer), the time step and the frame interval."""
    parameters = {k: v for k, v in scene.parameters.items() if k != "duration"}
    return {"scene": scene.name, "parameters": parameters, "dt": scene.dt, "frame_interval": scene.frame_interval,
            "nodes": scene.model.node_count}


def _check_same_run(path: Path, saved: dict, inputs: dict, nodes: int) -> None:
    """Refuse a checkpoint of a run asked for otherwise, naming what differs."""
    if "inputs" not in saved:
        raise InvalidInput(f"{path} records no inputs (written by an older party); remove it or drop --resume")
    theirs = json.loads(str(saved["inputs"]))
    ours = json.loads(json.dumps(inputs, sort_keys=True))
    if theirs.get("nodes") != ours["nodes"]:
        raise InvalidInput(f"{path} belongs to a different model ({theirs.get('nodes')} nodes, this one has "
                           f"{nodes}); remove it or drop --resume")
    differing = sorted(_differences(theirs, ours))
    if differing:
        raise InvalidInput(f"{path} belongs to another run (different {', '.join(differing)}); remove it or drop "
                           "--resume")


def _differences(theirs: dict, ours: dict, prefix: str = "") -> list[str]:
    """Names of the entries that differ, nested ones as ``parameters.fabric``."""
    names = []
    for key in theirs.keys() | ours.keys():
        a, b = theirs.get(key), ours.get(key)
        if isinstance(a, dict) and isinstance(b, dict) and key == "parameters":
            names += _differences(a, b, "")
        elif json.dumps(a, sort_keys=True) != json.dumps(b, sort_keys=True):
            names.append(prefix + key)
    return names


def memory_of(root, part: str) -> dict:
    """:func:`~party.solvers.memory.memory` of ``root``, its keys prefixed with ``part``."""
    return {f"{part}.{key}": value for key, value in memory(root).items()}


def saved_part(saved: dict, part: str) -> dict:
    """The entries :func:`memory_of` saved for ``part``."""
    cut = len(part) + 1
    return {key[cut:]: value for key, value in saved.items() if key.startswith(part + ".")}


MAX_RUN_SECONDS = 86400.0
"""Longest run [s of wall time] party starts without being told otherwise: a day. A run that
would take longer (a step far smaller than anyone means: ``--dt 1e-12``) is refused, naming the
step that would do."""

MIN_STEP_SECONDS = 1.0e-6
"""No step of any scene takes less than this [s]: step counts that would exceed a day even so
are refused before the first step."""

PACE_STEPS = 20
PACE_SECONDS = 1.0
"""The run's pace is judged once it has taken ``PACE_STEPS`` steps or ``PACE_SECONDS`` of wall
time after its first step (which compiles the kernels), whichever comes first."""


def _refuse_endless(steps: int, dt: float, seconds_per_step: float = MIN_STEP_SECONDS) -> None:
    """Refuse ``steps`` steps of ``dt`` [s] where at ``seconds_per_step`` [s] they would take
    longer than :data:`MAX_RUN_SECONDS`."""
    wall = steps * seconds_per_step
    if wall <= MAX_RUN_SECONDS:
        return
    needed = _round_up(dt * wall / MAX_RUN_SECONDS)
    raise InvalidInput(f"{steps:,} steps of {dt:g} s would take about {_duration(wall)} at "
                       f"{_duration(seconds_per_step)} a step; use a --dt of at least {needed:g} s, or a shorter "
                       "--duration")


class Pace:
    """Judges the run's time from its first steps (see :data:`PACE_STEPS`) and refuses one that
    would take longer than :data:`MAX_RUN_SECONDS`."""

    def __init__(self, steps: int, dt: float) -> None:
        self.steps, self.dt = steps, dt
        self.taken = 0
        self.started = 0.0
        self.judged = steps <= PACE_STEPS

    def stepped(self) -> None:
        if self.judged:
            return
        self.taken += 1
        if self.taken == 1:
            self.started = time.perf_counter()
            return
        elapsed = time.perf_counter() - self.started
        if self.taken - 1 >= PACE_STEPS or elapsed >= PACE_SECONDS:
            self.judged = True
            _refuse_endless(self.steps, self.dt, elapsed / (self.taken - 1))


def _duration(seconds: float) -> str:
    for unit, size in (("years", 3.15576e7), ("days", 86400.0), ("hours", 3600.0), ("minutes", 60.0), ("s", 1.0),
                       ("ms", 1e-3)):
        if seconds >= size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds * 1e6:.3g} us"


def _round_up(x: float) -> float:
    """A round number not below x (1, 2 or 5 times a power of ten)."""
    exp = np.floor(np.log10(x))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * 10**exp >= x:
            return float(m * 10**exp)
    return float(10 ** (exp + 1))


def _summary_numbers(totals: dict, frame: int, steps: int, dt: float) -> dict:
    return {
        "steps": steps, "simulated_seconds": steps * dt, "frames": frame + 1,
        "wall_seconds": round(totals["wall_seconds"], 3), "max_elongation": totals["max_elongation"],
        "body_penetrations": int(totals["body_penetrations"]), "cloth_crossings": int(totals["cloth_crossings"]),
    }


def _record(out, frame, points, faces, model, probe, limited, rest, totals) -> None:
    write_mesh(frame_path(out, frame), points, faces)
    totals["max_elongation"] = max(totals["max_elongation"], max_elongation(points, model.elements, rest, limited))
    totals["body_penetrations"] += probe.penetrations(points)
    totals["cloth_crossings"] += cloth_crossings(points, faces, model.device)


def _pictures(out: Path, scene: Scene, times: list[float], faces, colliders) -> None:
    import trimesh

    picks = np.unique(np.linspace(0, len(times) - 1, 8).round().astype(int))
    frames = []
    for k in picks:
        path = frame_path(out, k)
        if path.exists():
            pts = np.asarray(trimesh.load(path, process=False).vertices)
            frames.append((f"t = {times[k]:.2f} s", pts))
    if frames:
        images.render_sequence(out / "images" / "sequence.png", frames, faces, colliders, **scene.view)
        images.render_frame(out / "images" / "final.png", frames[-1][1], faces, colliders,
                            title=f"{scene.name}, {frames[-1][0]}", **scene.view)


def _round_down(x: float) -> float:
    """A round number not above x (1, 2 or 5 times a power of ten)."""
    exp = np.floor(np.log10(x))
    for m in (5.0, 2.0, 1.0):
        if m * 10**exp <= x:
            return float(m * 10**exp)
    return float(10**exp)
