"""``party drape``: a pattern, a body and a fabric in; a draped garment out.

Stages: read and check every input (nothing is written before all of them are good), mesh the
pattern, sew it onto the body (:func:`party.scenes.garment_sim.sew`), then relax the sewn
garment under gravity to static equilibrium, collisions on throughout. Output layout::

    OUT/garment.obj, OUT/garment.glb   draped garment with pattern UVs (metres, body's frame)
    OUT/body.obj                       the body as simulated (metres, body's frame)
    OUT/images/front.png, side.png, back.png, energy.png
    OUT/relaxation.json                energy logs of sewing and draping
    OUT/summary.json                   nodes, seams, max seam gap [mm], body_penetrations,
                                       cloth_crossings, relaxation iterations and final energy,
                                       wall_seconds
"""

from __future__ import annotations

import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from ..body.load import load_body
from ..body.probe import ColliderProbe
from ..errors import SimulationUnstable
from ..fabric import Fabric
from ..garment.assemble import assemble
from ..output.frames import write_json, write_mesh
from ..output.garment_export import write_garment
from ..output.metrics import cloth_crossings, max_elongation
from ..pattern import load_pattern
from ..solvers.relax import SolverRelax
from .garment_sim import garment_model, relax_progress, relax_time_step, sew

IMPLICIT_ITERATIONS = 1500
"""Most draping iterations with the implicit solver: its steps are 1/300 s, some 40 times the
explicit solver's, so it needs far fewer. Sewing always relaxes with explicit steps: with
implicit ones the seam springs pulled panels through each other (seen: seam gaps of 8-16 mm and
thousands of crossings on the reference dress and GarmentCode's flare dress)."""


def drape(pattern: Path, body: str, fabric: Fabric, out: Path, *, spacing: float = 0.02, device: str | None = None,
          pattern_units: str | None = None, body_units: str | None = None, up: str | None = None,
          seams_file: Path | None = None, sew_iterations: int = 6000, drape_iterations: int = 6000,
          images: bool = True, progress: bool = True, solver: str = "explicit") -> dict:
    """Drape ``pattern`` on ``body`` in ``fabric``; write results to ``out`` (see module docs).
    Results are assembled in a temporary folder beside ``out`` and moved in at the end, so a
    failed run leaves no half-written output."""
    started = time.perf_counter()
    the_pattern = load_pattern(pattern, seams_file=seams_file, units=pattern_units)
    the_body = load_body(body, units=body_units, up=up)
    garment = assemble(the_pattern, spacing)

    if solver == "implicit":
        drape_iterations = min(drape_iterations, IMPLICIT_ITERATIONS)
    sewn = sew(garment, the_body, fabric, device=device, max_iterations=sew_iterations, progress=progress)
    model = garment_model(sewn.net, fabric, sewn.points, the_body, device=device, name=the_pattern.name)
    state = model.state()
    with relax_progress("draping", drape_iterations, progress) as on_log:
        draped = SolverRelax(model, max_speed=1.0, momentum=0.9, solver=solver).relax(
            state, relax_time_step(model, solver), max_iterations=drape_iterations,
            min_iterations=min(300, drape_iterations), on_log=on_log)
    points = state.positions()
    if not np.all(np.isfinite(points)):
        raise SimulationUnstable("draping blew up (non-finite positions); try a coarser --spacing")

    host = model.host
    limited = host["element_params"][:, 3] < 1e29
    summary = {
        "pattern": str(pattern), "body": str(body), "fabric": fabric.name, "solver": solver, "spacing_m": spacing,
        "nodes": model.node_count, "triangles": model.triangle_count, "panels": len(the_pattern.panels),
        "seams": len(the_pattern.seams),
        "max_seam_gap_mm": round(1000.0 * sewn.max_seam_gap, 3),
        "seam_gaps_mm": {f"{s.a}-{s.b}": round(1000.0 * g, 3) for s, g in zip(the_pattern.seams, sewn.seam_gaps)},
        "body_penetrations": ColliderProbe(the_body.colliders, model.device).penetrations(points),
        "cloth_crossings": cloth_crossings(points, model.triangles, model.device),
        "max_elongation": max_elongation(points, host["elements"], host["element_params"][:, 0], limited),
        "relaxation": {
            "sewing_iterations": sewn.relaxation.iterations + sewn.settling.iterations, "draping_iterations": draped.iterations,
            "converged": bool(draped.converged), "final_energy_J": draped.final_energy,
        },
        "mesh_quality": garment.quality(),
    }

    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        in_file = the_body.to_file_frame
        write_garment(staging, "garment", in_file(points), model.triangles, garment.triangle_panel(), garment.corner_xy)
        for c in the_body.colliders:
            name = "body" if len(the_body.colliders) == 1 else f"body_{c.name}"
            write_mesh(staging / f"{name}.obj", in_file(c.vertices), c.faces)
        write_json(staging / "relaxation.json", {"sewing_energy_J": sewn.relaxation.energy,
                                                 "draping_energy_J": draped.energy})
        if images:
            _pictures(staging / "images", points, model.triangles, garment, the_body, sewn.relaxation.energy,
                      draped.energy)
        summary["wall_seconds"] = round(time.perf_counter() - started, 2)
        write_json(staging / "summary.json", summary)
        if out.exists():
            shutil.rmtree(out)
        staging.rename(out)
    finally:
        if staging.exists():
            shutil.rmtree(staging)
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
    for axis, log, title in ((ax[0], sewing_log, "sewing (no gravity)"), (ax[1], draping_log, "draping (gravity)")):
        if log:
            it, energy = np.array(log).T
            axis.plot(it, energy)
        axis.set_xlabel("iteration")
        axis.set_ylabel("energy [J]")
        axis.set_title(title)
    fig.tight_layout()
    fig.savefig(folder / "energy.png")
    plt.close(fig)
