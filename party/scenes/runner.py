"""Running a scene: stepping, frames written as they come, checks, checkpoints, resume.

Output layout of ``run_scene(scene, out)``:

- ``out/frames/frame_NNNNNN.ply``: the cloth at each output frame [m], names in time order;
- ``out/colliders/NAME.ply``: each collider once [m];
- ``out/images/``: ``sequence.png`` (panels through the run) and ``final.png``;
- ``out/summary.json``: counts, timings and checks (see :func:`run_scene`);
- ``out/checkpoint.npz``: the state after the last frame, to resume from.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import warp as wp
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from ..errors import InvalidInput, SimulationUnstable
from ..output import images
from ..output.frames import frame_path, load_checkpoint, save_checkpoint, write_json, write_mesh
from ..output.metrics import ColliderProbe, cloth_crossings, max_elongation
from ..solvers.explicit.solver import critical_time_step
from .scene import Scene

MAX_SPEED = 100.0
"""Node speed [m/s] taken as a blow-up: no garment motion comes near it."""


def run_scene(scene: Scene, out: Path, *, resume: bool = False, progress: bool = True) -> dict:
    """Simulate ``scene``, writing results under ``out`` as they are computed.

    Returns the summary (also written to ``out/summary.json``): nodes, steps (the scene's
    duration in whole steps; the last output frame is shorter where the duration ends within
    it), simulated_seconds, wall_seconds, max_elongation (largest length / rest length of any warp
    or weft element at any output frame), body_penetrations (nodes inside a collider, summed
    over output frames), cloth_crossings (crossing edge-triangle pairs, summed over output
    frames), and the scene's parameters. Raises :class:`SimulationUnstable` (frames so far
    kept, summary written with ``"status": "unstable"``) if the integration blows up.
    """
    model, dt = scene.model, scene.dt
    out = Path(out)
    critical = critical_time_step(model)
    if hasattr(scene.solver, "critical_time_step") and dt > critical:
        raise InvalidInput(f"time step {dt:g} s exceeds this net's explicit stability limit {critical:.3g} s; "
                           f"use --dt {_round_down(critical * 0.9):g} or a coarser --spacing")
    steps_per_frame = max(int(round(scene.frame_interval / dt)), 1)
    steps_total = max(int(round(scene.duration / dt)), 1)
    frames_total = -(-steps_total // steps_per_frame)  # the last frame shorter where the duration ends within it

    def steps_by(frame: int) -> int:
        return min(frame * steps_per_frame, steps_total)
    faces = model.triangles
    colliders = model.host["colliders"]
    host = model.host
    limited = model.limited_elements
    rest = host["element_params"][:, 0]
    probe = ColliderProbe(colliders, model.device)

    state, scratch = model.state(), model.state()
    control = model.control()
    checkpoint = out / "checkpoint.npz"
    summary_path = out / "summary.json"
    totals = {"max_elongation": 1.0, "body_penetrations": 0, "cloth_crossings": 0, "wall_seconds": 0.0}
    first_frame = 0
    steps_done = 0
    if resume and checkpoint.exists():
        saved = load_checkpoint(checkpoint)
        if saved["node_q"].shape != (model.node_count, 3):
            raise InvalidInput(f"{checkpoint} belongs to a different model ({len(saved['node_q'])} nodes, "
                               f"this one has {model.node_count}); remove it or drop --resume")
        state.node_q.assign(saved["node_q"])
        state.node_qd.assign(saved["node_qd"])
        state.collider_q.assign(saved["collider_q"])
        state.collider_qd.assign(saved["collider_qd"])
        state.time = float(saved["time"])
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
                if hasattr(scene.solver, "end"):  # a crossing check the guard's interval left pending
                    scene.solver.end.flush(state)
                wp.synchronize_device(model.device)
                totals["wall_seconds"] += time.perf_counter() - start
                points = state.positions()
                speed = np.linalg.norm(state.velocities(), axis=1).max() if model.node_count else 0.0
                if not np.all(np.isfinite(points)) or not speed < MAX_SPEED:
                    raise SimulationUnstable(
                        f"simulation became unstable before t = {state.time:.4f} s (max node speed "
                        f"{speed:.3g} m/s); frames up to {frame - 1} are kept in {out / 'frames'}; "
                        f"try a smaller --dt, e.g. {_round_down(dt / 2):g}")
            except SimulationUnstable:
                summary.update(_summary_numbers(totals, frame - 1, steps_done, dt), status="unstable")
                write_json(summary_path, summary)
                raise
            _record(out, frame, points, faces, model, probe, limited, rest, totals)
            save_checkpoint(checkpoint, node_q=points.astype(np.float32), node_qd=state.velocities().astype(np.float32),
                            collider_q=state.collider_q.numpy(), collider_qd=state.collider_qd.numpy(),
                            time=state.time, frame=frame, **{k: v for k, v in totals.items()})
            steps_done = steps_by(frame)
            summary.update(_summary_numbers(totals, frame, steps_done, dt))
            write_json(summary_path, summary)
            bar.update(task, completed=frame, t=state.time)

    summary["status"] = "finished"
    write_json(summary_path, summary)
    times = [steps_by(k) * dt for k in range(frames_total + 1)]
    if scene.pictures is not None:
        scene.pictures(out, [(t, frame_path(out, k)) for k, t in enumerate(times)])
    else:
        _pictures(out, scene, times, faces, colliders)
    return summary


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
