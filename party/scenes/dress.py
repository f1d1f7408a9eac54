"""Experiment 2 of the paper (section 7, figures 12-14): a one-piece dress with sleeves.

The dress (bodice front and back, skirt front and back, two set-in sleeves; our pattern file
``party/data/patterns/dress_sleeves.json``) is meshed and sewn onto the ellipse dress form,
relaxed ignoring inertia until its energy settles (figure 12: sleeves straight out), then
simulated in wool flannel (Table 1) at dt = 1e-4 s while the sleeves fall under gravity. The
net is drawn as a wireframe every 1000 steps (figure 13) and the final shape is rendered from
the front, the side and the back (figure 14). Beyond the paper, the crossing guard
(:mod:`party.collision.crossing_guard`) is on during the fall, checking every 1/300 s: without
it the sleeves' folds let some edges through neighbouring triangles.

Run with an output folder (``party run dress --out OUT``), the sewing keeps ``OUT/sewn.npz``
as it goes (after each of its stages, and once sewn: :mod:`.drape_checkpoint`), and
``--resume`` takes the sewn garment from there instead of sewing it again (some 15 s at the
default spacing), or goes on with a sewing that was stopped.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from importlib import resources
from pathlib import Path

import numpy as np
import trimesh

from ..body.dress_form import dress_form
from ..collision.presets import guarded
from ..fabric import Fabric, wool_flannel
from ..garment.assemble import assemble
from ..garment.sewing import SewingSettings, sew
from ..garment.worn import garment_model
from ..output import render
from ..output.frames import write_json
from ..pattern import load_pattern
from ..solvers.explicit.solver import PAPER_DT
from ..solvers.registry import make_solver, solver_class
from .drape_checkpoint import DrapeCheckpoint, Saved
from .scene import Scene, check_timing

PATTERN = "dress_sleeves.json"
WIREFRAME_EVERY = 1000
"""Steps of PAPER_DT between wireframe drawings (figure 13), whichever solver runs."""
SEWING_CHECKPOINT = "sewn.npz"
"""The sewing's checkpoint in the output folder."""


def pattern_path() -> Path:
    return Path(str(resources.files("party.data").joinpath("patterns", PATTERN)))


@dataclass(frozen=True)
class Settings:
    """The dress's options (``party run dress``): the net's ``spacing`` [m] (default 15 mm, with
    ``quick`` 30 mm), ``duration`` [s] of the fall (default 1.2, with ``quick`` 0.3), the step
    ``dt`` [s] (default: the solver's, the paper's 1e-4 s for the explicit one), the dress form's
    ``size``, the solver and the fabric (default: the paper's wool flannel). ``quick`` also
    sews in fewer iterations."""

    spacing: float | None = None
    duration: float | None = None
    dt: float | None = None
    quick: bool = False
    size: str = "M"
    solver: str = "explicit"
    fabric: Fabric | None = None


def build(settings: Settings = Settings(), *, device: str | None = None, out: Path | None = None,
          resume: bool = False, progress: bool = False, on_save: Saved | None = None) -> Scene:
    """The dress as ``settings`` say, its kernels on ``device``. With ``out`` the sewing is kept
    in ``out/sewn.npz`` (``on_save`` hears of each save), and with ``resume`` taken from there
    (see the module docstring; one for another spacing, size, fabric or quickness is refused)."""
    solver, quick = settings.solver, settings.quick
    dt = solver_class(solver).default_dt if settings.dt is None else settings.dt
    spacing = settings.spacing if settings.spacing is not None else 0.03 if quick else 0.015
    duration = settings.duration if settings.duration is not None else 0.3 if quick else 1.2
    check_timing(duration, dt)
    fabric = settings.fabric or wool_flannel()
    body = dress_form(settings.size)
    garment = assemble(load_pattern(pattern_path()), spacing)
    sewing = SewingSettings(max_iterations=3000 if quick else 8000)
    if out is None:
        sewn = sew(garment, body, fabric, sewing, device=device, progress=progress)
    else:
        inputs = {"scene": "dress", "spacing_m": spacing, "body": body.name, "fabric": fabric.to_dict(),
                  "sewing": asdict(sewing)}
        checkpoint = DrapeCheckpoint(Path(out) / SEWING_CHECKPOINT, inputs, run="dress sewing", on_save=on_save)
        saved = checkpoint.load() if resume else None
        sewn = checkpoint.sew(saved, checkpoint.wall_clock(saved, time.perf_counter()), garment, body, fabric, sewing,
                              device=device, progress=progress)
    model = garment_model(sewn.net, fabric, sewn.points, body, device=device, name="dress",
                          ignored_parts=sewn.ignored_parts())
    scene = Scene(
        name="dress", model=model, solver=make_solver(solver, model, collision=guarded(dt)),
        dt=dt, duration=duration,
        frame_interval=WIREFRAME_EVERY * PAPER_DT / 2,
        parameters={"spacing": spacing, "duration": duration, "dt": dt, "fabric": fabric.to_dict(), "body": body.name,
                    "quick": quick, "solver": solver},
        summary={"seams": len(garment.pattern.seams), "max_seam_gap_mm": round(1000 * sewn.max_seam_gap, 3),
                 "relaxation": {"iterations": sewn.relaxation.iterations + sewn.settling.iterations,
                                "converged": sewn.settling.converged,
                                "final_energy_J": sewn.settling.final_energy, "dt": sewn.dt},
                 "mesh_quality": garment.quality()},
    )
    scene.pictures = lambda out, frames: _pictures(out, frames, sewn, body, scene)
    return scene


def _pictures(out: Path, frames: list, sewn, body, scene: Scene) -> None:
    """Figures 12-14 and the sleeve-fall animation, under ``out/images``."""
    images = out / "images"
    garment = sewn.garment
    write_json(out / "relaxation.json", {"sewing_energy_J": sewn.relaxation.energy,
                                         "settling_energy_J": sewn.settling.energy})
    tri, panel, corners = sewn.net.triangles, garment.triangle_panel(), garment.corner_xy

    def points(path: Path) -> np.ndarray:
        return np.asarray(trimesh.load(path, process=False).vertices)

    first = points(frames[0][1])
    camera = render.framing(first, 2.0)
    shaded = render.GarmentRenderer(tri, panel, corners, body.colliders)
    shaded.pose(first)
    shaded.render(images / "initial_shape.png", "three_quarter", **camera)
    shaded.pose(points(frames[-1][1]))
    for view in ("front", "side", "back"):
        shaded.render(images / f"final_{view}.png", view, **camera)
    stills = []
    for t, path in frames:
        shaded.pose(points(path))
        stills.append(shaded.image("front", **camera)[::2, ::2])
    shaded.close()
    render.save_gif(stills, images / "sleeve_fall.gif", seconds_per_frame=max(frames[1][0] - frames[0][0], 0.05))

    wire = render.GarmentRenderer(tri, panel, corners, body.colliders, size=400, wireframe=True)
    picks = frames[::2]
    shots, labels = [], []
    for t, path in picks:
        wire.pose(points(path))
        shots.append(wire.image("front", **camera))
        labels.append(f"step {int(round(t / PAPER_DT))}" if scene.dt == PAPER_DT else f"t = {t:.2f} s")
    wire.close()
    render.tile(shots, labels, images / "wireframe_sequence.png", columns=min(len(shots), 6))
