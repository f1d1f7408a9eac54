"""``party drape``: a pattern, a body and a fabric in; a draped garment out.

Stages: read and check every input (nothing is written before all of them are good), mesh the
pattern, sew it onto the body (:func:`party.garment.sewing.sew`), then drape the sewn garment
under gravity as its solver drapes (:mod:`party.garment.draping`). Sewing always relaxes with
explicit steps: in implicit steps the seam springs pull whole regions of the panels through
each other at once. Output layout::

    OUT/garment.obj, OUT/garment.glb   draped garment with pattern UVs (metres, body's frame)
    OUT/body.obj                       the body as simulated (metres, body's frame)
    OUT/images/front.png, side.png, back.png, energy.png
    OUT/relaxation.json                energy logs of sewing and draping
    OUT/summary.json                   nodes, seams, max seam gap [mm], body_penetrations,
                                       body_distance_mm (nearest, median,
                                       near_share: the share within 50 mm),
                                       body_vertices_through_cloth, cloth_crossings,
                                       max_elongation (draped) and
                                       max_sewn_elongation (as sewn; above the fabric's
                                       limit where the pattern is smaller than the body,
                                       or its sewing had not settled),
                                       relaxation (sewing iterations, draping steps and
                                       simulated seconds, at_rest, final energy [J]),
                                       quality (passed, reasons: :mod:`party.output.quality`),
                                       time_limit_s, timed_out, where (the panels and
                                       the stage of each fault: :mod:`party.output.locate`),
                                       wall_seconds (resumed drapes: all runs')
    OUT/checkpoint.npz                 while it runs: the sewing after each of its stages,
                                       the sewn garment, then the draping state,
                                       which ``resume`` goes on from (:mod:`.drape_checkpoint`);
                                       gone once the drape finishes, kept where
                                       it stopped at its time limit
"""

from __future__ import annotations

import os
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..body.load import load_body
from ..body.probe import ColliderProbe
from ..errors import SimulationUnstable
from ..fabric import Fabric
from ..garment.assemble import assemble
from ..garment.checks import check_placement, estimate_nodes
from ..garment.draping import DRAPING
from ..garment.sewing import SewingSettings
from ..garment.worn import garment_model
from ..model import State
from ..output.folder import check_output_path, open_output
from ..output.frames import write_json, write_mesh
from ..output.garment_export import write_garment
from ..output.metrics import body_vertices_through, crossing_edges, elements_beyond_limit, max_elongation
from ..output.locate import locate
from ..output.quality import NEAR_MM, drape_quality
from ..pattern import load_pattern
from ..resources import DRAPE_FOOTPRINT, check_memory, check_time_limit
from ..solvers.registry import check_solver
from .drape_checkpoint import SAVE_SECONDS, DrapeCheckpoint, Saved, restore_draping


@dataclass(frozen=True)
class DrapeSettings:
    """What ``party drape`` is asked for besides its pattern, body and fabric.

    Attributes:
        spacing: Node spacing of the net [m].
        solver: The solver that drapes (its name; :mod:`party.solvers.registry`).
        device: Where the kernels run (None: :func:`party.device.resolve`'s choice).
        pattern_units, seams_file: A DXF pattern's length unit and seams side file.
        body_units, up: A body mesh's length unit and up axis (None: detected).
        sewing: How the garment is sewn.
        images: Render front, side and back views.
        progress: Show progress on the terminal.
        resume: Go on from the output folder's checkpoint.
        overwrite: Write into an output folder that holds files party did not write.
        checkpoint_seconds: Least wall time [s] between two checkpoints while draping.
        time_limit: Wall time [s] a drape may take, all its runs together: past it the sewing
            finishes what it must to join the garment and the draping stops where it is; the
            result is written, its checkpoint kept (a resume with a larger limit goes on), and
            its quality gate says so. GarmentCode's own allowance per garment is 600 s.
    """

    spacing: float = 0.02
    solver: str = "explicit"
    device: str | None = None
    pattern_units: str | None = None
    seams_file: Path | None = None
    body_units: str | None = None
    up: str | None = None
    sewing: SewingSettings = field(default_factory=SewingSettings)
    images: bool = True
    progress: bool = True
    resume: bool = False
    overwrite: bool = False
    checkpoint_seconds: float = SAVE_SECONDS
    time_limit: float = 600.0

    def __post_init__(self) -> None:
        check_solver(self.solver)
        check_time_limit(self.time_limit)


def drape(pattern: Path, body: str, fabric: Fabric, out: Path, settings: DrapeSettings = DrapeSettings(), *,
          on_save: Saved | None = None) -> dict:
    """Drape ``pattern`` on ``body`` in ``fabric``; write results to ``out`` (see module docs).

    ``out`` is taken as party's output folder (:mod:`party.output.folder`: refused where it
    holds files party did not write, unless ``settings.overwrite``; locked while the drape runs).
    Every input is read and checked before the folder is taken and any work is done. Results
    are assembled in a staging folder inside ``out`` and moved in at the end, replacing only
    the drape's own files, so a failed run leaves no half-written output, only
    ``out/checkpoint.npz``, which a run with ``settings.resume`` goes on from (the stages done
    not repeated; see :mod:`.drape_checkpoint`, whose ``on_save`` hears of every checkpoint)."""
    started = time.perf_counter()
    check_output_path(Path(out))
    spacing, device, progress = settings.spacing, settings.device, settings.progress
    the_pattern = load_pattern(pattern, seams_file=settings.seams_file, units=settings.pattern_units)
    the_body = load_body(body, units=settings.body_units, up=settings.up)
    check_placement(the_pattern, the_body, str(pattern))
    nodes = estimate_nodes(the_pattern, spacing)
    check_memory(DRAPE_FOOTPRINT, nodes, spacing)
    body_file = Path(body)
    inputs = {"pattern": str(Path(pattern).resolve()), "body": str(body_file.resolve()) if body_file.exists() else body,
              "fabric": fabric.to_dict(), "spacing_m": spacing, "solver": settings.solver,
              "sewing": asdict(settings.sewing), "pattern_units": settings.pattern_units,
              "body_units": settings.body_units, "up": settings.up,
              "seams_file": None if settings.seams_file is None else str(Path(settings.seams_file).resolve())}
    with open_output(out, "drape", overwrite=settings.overwrite, description=Path(pattern).name) as folder:
        if progress:
            print(f"meshing {len(the_pattern.panels)} panels at {1000 * spacing:g} mm: about {nodes:,} nodes", flush=True)
        garment = assemble(the_pattern, spacing)
        checkpoint = DrapeCheckpoint(folder.path / "checkpoint.npz", inputs, save_every=settings.checkpoint_seconds,
                                     on_save=on_save)
        saved = checkpoint.load() if settings.resume else None
        wall = checkpoint.wall_clock(saved, started)

        def time_is_up() -> bool:
            return wall() > settings.time_limit

        sewn = checkpoint.sew(saved, wall, garment, the_body, fabric, settings.sewing, device=device, progress=progress,
                              stop=time_is_up)
        model = garment_model(sewn.net, fabric, sewn.points, the_body, device=device, name=the_pattern.name,
                              ignored_parts=sewn.ignored_parts())
        state = model.state()
        first_step, energy = restore_draping(state, saved)

        def save(step: int, log: list, state: State) -> None:
            checkpoint.save_draping(state, step, log, wall())

        draped, energy = DRAPING[settings.solver].run(model, state, first_step, energy, save, progress,
                                                      stop=time_is_up)
        points = draped.state.positions()
        if not np.all(np.isfinite(points)):
            raise SimulationUnstable("draping blew up (non-finite positions); try a coarser --spacing")
        timed_out = time_is_up()
        summary = _summary(pattern, body, fabric, settings, the_pattern, the_body, garment, sewn, model, points,
                           draped, energy, timed_out)
        staging = folder.staging()
        if timed_out:
            checkpoint.save_draping(draped.state, draped.steps, energy, wall(), now=True)
            os.replace(checkpoint.path, staging / checkpoint.path.name)
        in_file = the_body.to_file_frame
        write_garment(staging, "garment", in_file(points), model.triangles, garment.triangle_panel(), garment.corner_xy)
        for c in the_body.colliders:
            name = "body" if len(the_body.colliders) == 1 else f"body_{c.name}"
            write_mesh(staging / f"{name}.obj", in_file(c.vertices), c.faces)
        write_json(staging / "relaxation.json", {"sewing_energy_J": sewn.relaxation.energy,
                                                 "draping_energy_J": energy})
        if settings.images:
            _pictures(staging / "images", points, model.triangles, garment, the_body, sewn.relaxation.energy, energy)
        summary["wall_seconds"] = round(wall(), 2)
        write_json(staging / "summary.json", summary)
        folder.publish(staging)
    return summary


def _summary(pattern, body, fabric: Fabric, settings: DrapeSettings, the_pattern, the_body, garment, sewn, model,
             points: np.ndarray, draped, energy: list, timed_out: bool) -> dict:
    """The drape's ``summary.json`` (see the module docstring), its quality gates included
    (:func:`party.output.quality.drape_quality`)."""
    host = model.host
    limited = model.limited_elements
    probe = ColliderProbe(the_body.colliders, model.device)
    inside, distance = probe.inside_and_distance(points, ignored_parts=host.ignored_parts)
    crossings = crossing_edges(points, model.triangles, model.device)
    summary = {
        "pattern": str(pattern), "body": str(body), "fabric": fabric.name, "solver": settings.solver,
        "spacing_m": settings.spacing,
        "nodes": model.node_count, "triangles": model.triangle_count, "panels": len(the_pattern.panels),
        "seams": len(the_pattern.seams),
        "max_seam_gap_mm": round(1000.0 * sewn.max_seam_gap, 3),
        "seam_gaps_mm": {f"{s.a}-{s.b}": round(1000.0 * g, 3) for s, g in zip(the_pattern.seams, sewn.seam_gaps)},
        "body_penetrations": int(inside.sum()),
        "body_distance_mm": {"nearest": round(1000.0 * float(distance.min()), 3),
                             "median": round(1000.0 * float(np.median(distance)), 3),
                             "near_share": round(float((distance < NEAR_MM / 1000.0).mean()), 4)},
        "cloth_crossings": crossings[0],
        "body_vertices_through_cloth": body_vertices_through(points, model.triangles, the_body.colliders,
                                                             device=model.device),
        "max_elongation": max_elongation(points, host.elements, host.element_rest_length, limited),
        "max_sewn_elongation": max_elongation(sewn.points, host.elements, host.element_rest_length, limited),
        "elements_beyond_limit": elements_beyond_limit(points, host.elements, model.element_max_length.numpy()),
        "relaxation": {
            "sewing_iterations": sewn.relaxation.iterations + sewn.settling.iterations, "draping_steps": draped.steps,
            "draping_seconds": round(draped.seconds, 3), "at_rest": draped.at_rest,
            "final_energy_J": energy[-1][1] if energy else float("nan"),
        },
        "mesh_quality": garment.quality(),
        "time_limit_s": settings.time_limit,
        "timed_out": timed_out,
        "where": locate(points, sewn.points, host.elements, host.element_rest_length, limited, inside,
                        probe.inside_and_distance(sewn.points, ignored_parts=host.ignored_parts)[0], model.triangles,
                        crossings, garment.triangle_panel(), list(the_pattern.panels), model.device),
    }
    summary["quality"] = drape_quality(summary, fabric.thickness)
    return summary


def _pictures(folder: Path, points, triangles, garment, body, sewing_log, draping_log) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..output import render

    r = render.GarmentRenderer(triangles, garment.triangle_panel(), garment.corner_xy, body.colliders, size=1024)
    r.pose(points)
    camera = render.framing(body.vertices(), 2.2)
    for view in ("front", "side", "back"):
        r.render(folder / f"{view}.png", view, **camera)
    r.close()
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    for axis, log, title, x in ((ax[0], sewing_log, "sewing (no gravity)", "iteration"),
                                (ax[1], draping_log, "draping (gravity)", "step")):
        if log:
            it, energy = np.array(log).T
            axis.plot(it, energy)
        axis.set_xlabel(x)
        axis.set_ylabel("energy [J]")
        axis.set_title(title)
    fig.tight_layout()
    fig.savefig(folder / "energy.png")
    plt.close(fig)
