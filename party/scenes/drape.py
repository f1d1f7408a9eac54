"""``party drape``: a pattern, a body and a fabric in; a draped garment out.

Stages: read and check every input (nothing is written before all of them are good), mesh the
pattern, sew it onto the body (:func:`party.scenes.garment_sim.sew`), then relax the sewn
garment under gravity, collisions on throughout: with the explicit solver as the sewing is
relaxed, with kinetic damping until the energy settles (:func:`_relax_kinetically`); with the
implicit one by damped dynamics until its shape is steady (:func:`_drape_to_rest`). Sewing
always relaxes with explicit steps: with implicit ones the seam springs pulled panels through
each other (seen: seam gaps of 8-16 mm and thousands of crossings on the reference dress and
GarmentCode's flare dress). Output layout::

    OUT/garment.obj, OUT/garment.glb   draped garment with pattern UVs (metres, body's frame)
    OUT/body.obj                       the body as simulated (metres, body's frame)
    OUT/images/front.png, side.png, back.png, energy.png
    OUT/relaxation.json                energy logs of sewing and draping
    OUT/summary.json                   nodes, seams, max seam gap [mm], body_penetrations,
                                       body_vertices_through_cloth, cloth_crossings,
                                       max_elongation (draped) and
                                       max_sewn_elongation (as sewn; above the fabric's
                                       limit where the pattern is smaller than the body,
                                       or its sewing had not settled),
                                       relaxation (sewing iterations, draping steps and
                                       simulated seconds, at_rest, final energy [J]),
                                       wall_seconds (resumed drapes: all runs')
    OUT/checkpoint.npz                 while it runs: the sewing after each of its stages,
                                       the sewn garment, then the draping state,
                                       which ``resume`` goes on from (:mod:`.drape_checkpoint`);
                                       gone once the drape finishes
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

import numpy as np

from ..body.load import load_body
from ..body.probe import ColliderProbe
from ..collision import CollisionSettings
from ..errors import SimulationUnstable
from ..fabric import Fabric
from ..garment.assemble import assemble
from ..garment.checks import check_placement, estimate_nodes
from ..output.frames import write_json, write_mesh
from ..output.folder import check_output_path, open_output
from ..output.garment_export import write_garment
from ..output.metrics import body_vertices_through, cloth_crossings, elements_beyond_limit, max_elongation
from ..output.quality import drape_quality
from ..pattern import load_pattern
from ..resources import DRAPE_FOOTPRINT, check_memory
from ..model import Model, State
from ..solvers.relax import RelaxResult, SolverRelax, total_energy
from ..solvers.select import guard_every
from ..solvers.settle import DRAPE_SWEEPS, Settled, settle
from .drape_checkpoint import DrapeCheckpoint, restore_draping
from .garment_sim import garment_model, relax_progress, relax_time_step

EXPLICIT_ITERATIONS = 6000
"""Most iterations of the explicit solver's drape (:mod:`party.solvers.relax`): it stops when
the energy settles. Its kinetic damping keeps 0.9 of the velocity per step, which at
the explicit solver's small steps lets a sleeve fall 2 cm/s at most: sleeves sewn out
sideways stay out (the paper's figure 12), as they do in ``party run dress`` before its fall."""

DRAPE_MEMORY = 0.1
"""Drag time constant of the implicit solver's drape [s] (:func:`party.solvers.settle.settle`):
near critical for a sleeve swinging down from the sewing pose."""

DRAPE_MAX_SPEED = 0.5
"""Speed cap of the implicit solver's drape [m/s], the terminal speed of a fall under that drag."""

DRAPE_CHECK = 0.5
"""The implicit solver's drape checks the garment's shape every this long [s] of simulated time ..."""

STEADY_MEAN = 1.0e-3
STEADY_P99 = 1.0e-2
"""... and it is draped (at rest) when, over two checks, its nodes moved less than
``STEADY_MEAN`` [m] on average and 99 % of them less than ``STEADY_P99`` [m]. Not every node
stops: the implicit solver's truncated sweeps leave each node jittering by some 30 um a step
(mean speed 2 mm/s on the reference dress), and nodes at a coarse flared hem slip now and then
(GarmentCode's flare dress at 30 mm: 1 % of the nodes moved 5 mm or more in every 0.5 s), once
the shape has stopped changing. (Until this stop it relaxed like the explicit solver, and its
energy, jittering by 3 %, met the criterion by chance while the sleeves were still falling at
6 cm/s.)"""

DRAPE_SECONDS = 10.0
"""Most simulated time [s] the implicit solver's drape may take; a garment still moving then
is written anyway, with ``at_rest`` false in its summary."""


def drape(pattern: Path, body: str, fabric: Fabric, out: Path, *, spacing: float = 0.02, device: str | None = None,
          pattern_units: str | None = None, body_units: str | None = None, up: str | None = None,
          seams_file: Path | None = None, sew_iterations: int = 6000, images: bool = True, progress: bool = True,
          solver: str = "explicit", resume: bool = False, overwrite: bool = False) -> dict:
    """Drape ``pattern`` on ``body`` in ``fabric``; write results to ``out`` (see module docs).

    ``out`` is taken as party's output folder (:mod:`party.output.folder`: refused where it
    holds files party did not write, unless ``overwrite``; locked while the drape runs). Every
    input is read and checked before the folder is taken and any work is done. Results are
    assembled in a staging folder inside ``out`` and moved in at the end, replacing only the
    drape's own files, so a failed run leaves no half-written output, only
    ``out/checkpoint.npz``, which a run with ``resume`` goes on from (the stages done not
    repeated; see :mod:`.drape_checkpoint`)."""
    started = time.perf_counter()
    check_output_path(Path(out))
    the_pattern = load_pattern(pattern, seams_file=seams_file, units=pattern_units)
    the_body = load_body(body, units=body_units, up=up)
    check_placement(the_pattern, the_body, str(pattern))
    nodes = estimate_nodes(the_pattern, spacing)
    check_memory(DRAPE_FOOTPRINT, nodes, spacing)
    body_file = Path(body)
    inputs = {"pattern": str(Path(pattern).resolve()), "body": str(body_file.resolve()) if body_file.exists() else body,
              "fabric": fabric.to_dict(), "spacing_m": spacing, "solver": solver, "sew_iterations": sew_iterations,
              "pattern_units": pattern_units, "body_units": body_units, "up": up,
              "seams_file": None if seams_file is None else str(Path(seams_file).resolve())}
    with open_output(out, "drape", overwrite=overwrite, description=Path(pattern).name) as folder:
        if progress:
            print(f"meshing {len(the_pattern.panels)} panels at {1000 * spacing:g} mm: about {nodes:,} nodes", flush=True)
        garment = assemble(the_pattern, spacing)
        checkpoint = DrapeCheckpoint(folder.path / "checkpoint.npz", inputs)
        saved = checkpoint.load() if resume else None
        wall = checkpoint.wall_clock(saved, started)
        sewn = checkpoint.sew(saved, wall, garment, the_body, fabric, device=device, max_iterations=sew_iterations,
                              progress=progress)
        model = garment_model(sewn.net, fabric, sewn.points, the_body, device=device, name=the_pattern.name)
        state = model.state()
        first_step, energy = restore_draping(state, saved)

        def save(step: int, log: list, state: State) -> None:
            checkpoint.save_draping(state, step, log, wall())

        draped, energy = (_drape_to_rest if solver == "implicit" else _relax_kinetically)(
            model, state, first_step, energy, save, progress)
        points = draped.state.positions()
        if not np.all(np.isfinite(points)):
            raise SimulationUnstable("draping blew up (non-finite positions); try a coarser --spacing")
        summary = _summary(pattern, body, fabric, solver, spacing, the_pattern, the_body, garment, sewn, model,
                           points, draped, energy)
        staging = folder.staging()
        in_file = the_body.to_file_frame
        write_garment(staging, "garment", in_file(points), model.triangles, garment.triangle_panel(), garment.corner_xy)
        for c in the_body.colliders:
            name = "body" if len(the_body.colliders) == 1 else f"body_{c.name}"
            write_mesh(staging / f"{name}.obj", in_file(c.vertices), c.faces)
        write_json(staging / "relaxation.json", {"sewing_energy_J": sewn.relaxation.energy,
                                                 "draping_energy_J": energy})
        if images:
            _pictures(staging / "images", points, model.triangles, garment, the_body, sewn.relaxation.energy, energy)
        summary["wall_seconds"] = round(wall(), 2)
        write_json(staging / "summary.json", summary)
        folder.publish(staging)
    return summary


def _summary(pattern, body, fabric: Fabric, solver: str, spacing: float, the_pattern, the_body, garment, sewn, model,
             points: np.ndarray, draped: Settled, energy: list) -> dict:
    """The drape's ``summary.json`` (see the module docstring), its quality gates included
    (:func:`party.output.quality.drape_quality`)."""
    host = model.host
    limited = model.limited_elements
    inside, distance = ColliderProbe(the_body.colliders, model.device).inside_and_distance(points)
    summary = {
        "pattern": str(pattern), "body": str(body), "fabric": fabric.name, "solver": solver, "spacing_m": spacing,
        "nodes": model.node_count, "triangles": model.triangle_count, "panels": len(the_pattern.panels),
        "seams": len(the_pattern.seams),
        "max_seam_gap_mm": round(1000.0 * sewn.max_seam_gap, 3),
        "seam_gaps_mm": {f"{s.a}-{s.b}": round(1000.0 * g, 3) for s, g in zip(the_pattern.seams, sewn.seam_gaps)},
        "body_penetrations": int(inside.sum()),
        "body_distance_mm": {"nearest": round(1000.0 * float(distance.min()), 3),
                             "median": round(1000.0 * float(np.median(distance)), 3)},
        "cloth_crossings": cloth_crossings(points, model.triangles, model.device),
        "body_vertices_through_cloth": body_vertices_through(points, model.triangles, the_body.colliders,
                                                             device=model.device),
        "max_elongation": max_elongation(points, host["elements"], host["element_params"][:, 0], limited),
        "max_sewn_elongation": max_elongation(sewn.points, host["elements"], host["element_params"][:, 0], limited),
        "elements_beyond_limit": elements_beyond_limit(points, host["elements"], model.element_max_length.numpy()),
        "relaxation": {
            "sewing_iterations": sewn.relaxation.iterations + sewn.settling.iterations, "draping_steps": draped.steps,
            "draping_seconds": round(draped.seconds, 3), "at_rest": draped.at_rest,
            "final_energy_J": energy[-1][1] if energy else float("nan"),
        },
        "mesh_quality": garment.quality(),
    }
    summary["quality"] = drape_quality(summary, fabric.thickness)
    return summary


Saver = Callable[[int, list, State], None]
"""``on_save(step, energy log [(step, J)], state)``: a drape's checkpoint, called at each check."""


def _drape_to_rest(model: Model, state: State, first_step: int, energy: list[tuple[int, float]], on_save: Saver,
                   progress: bool) -> tuple[Settled, list[tuple[int, float]]]:
    """Implicit steps: the sewn garment let fall under gravity until its shape is steady (see
    :data:`STEADY_MEAN`), with the implicit solver's collisions (the crossing guard and body
    vertices on: :func:`~party.solvers.select.large_step_collision`), from ``state`` after
    ``first_step`` steps that logged ``energy``; ``on_save(step, energy, state)`` at every
    check; returns the outcome and the energy [J] logged at each check against the step."""
    energy = list(energy)
    with relax_progress("draping", int(DRAPE_SECONDS / DRAPE_CHECK), progress) as on_log:
        def on_check(step: int, state) -> None:
            energy.append((step, total_energy(model, state.positions())))
            on_log(len(energy), energy[-1][1], state)
            on_save(step, energy, state)

        settled = settle(model, "implicit", memory=DRAPE_MEMORY, check_every=DRAPE_CHECK, max_seconds=DRAPE_SECONDS,
                         rest_speed=0.0, steady=_shape_steady, on_check=on_check, max_speed=DRAPE_MAX_SPEED,
                         iterations=DRAPE_SWEEPS, state=state, first_step=first_step)
    return settled, energy


def _relax_kinetically(model: Model, state: State, first_step: int, energy: list[tuple[int, float]], on_save: Saver,
                       progress: bool) -> tuple[Settled, list[tuple[int, float]]]:
    """Explicit steps: the relaxation of :mod:`party.solvers.relax` (section 7's iteration, with
    kinetic damping) until the energy settles (to 0.2 % over 300 iterations) or
    :data:`EXPLICIT_ITERATIONS`, the crossing guard checking every 1/300 s of its steps, as in
    ``party run dress``, and once more when it stops (GarmentCode's tshirt in denim ended with 9
    crossings without the guard, 4 without that last check, none with both), and the body's
    vertices held off the cloth's triangles (:mod:`party.collision.body_vertices`: GarmentCode's
    samples at 30 mm had 14 to 551 of them through the cloth without, 0 to 2 with), the plastic
    limit enforced again after that (without, the body vertices' push on the jumpsuit's tight
    hems at 20 mm stretched them to 5.5 times rest, against a limit of 1.4); returns the
    outcome (``at_rest``: the energy settled) and the energy log [J] against the iteration;
    ``state``, ``first_step``, ``energy`` and ``on_save`` as for :func:`_drape_to_rest`, at every log."""
    dt = relax_time_step(model, "explicit")
    with relax_progress("draping", EXPLICIT_ITERATIONS, progress) as on_log:
        logged = list(energy)

        def on_log_and_save(iteration: int, energy_now: float, state) -> None:
            on_log(iteration, energy_now, state)
            logged.append((iteration, energy_now))
            on_save(iteration, logged, state)

        guarded = CollisionSettings(crossing_guard=True, guard_every=guard_every(dt), body_vertices=True)
        relaxed = SolverRelax(model, collision=guarded, max_speed=1.0, momentum=0.9, solver="explicit").relax(
            state, dt, max_iterations=EXPLICIT_ITERATIONS, min_iterations=300, on_log=on_log_and_save,
            resumed=RelaxResult(first_step, list(energy)))
    return Settled(state, relaxed.iterations, relaxed.iterations * dt, relaxed.converged), relaxed.energy


def _shape_steady(before: np.ndarray, after: np.ndarray) -> bool:
    moved = np.linalg.norm(after - before, axis=1)
    return float(moved.mean()) < STEADY_MEAN and float(np.percentile(moved, 99)) < STEADY_P99


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
