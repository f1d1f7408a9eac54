"""The ``party`` command."""

from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path
from typing import Optional

import typer
from rich.console import Console

from .errors import INTERRUPTED, InvalidInput, PartyError

app = typer.Typer(add_completion=False, no_args_is_help=True, rich_markup_mode=None,
                  help="PARTY dress simulator: the paper's experiments and garment draping.")
err = Console(stderr=True)
out = Console()

OPEN_SEAM_MM = 1.0
"""A seam gap [mm] beyond which ``party drape`` warns (the sewing closes seams to 0.5 mm)."""


@app.command("scenes")
def scenes_command() -> None:
    """List the scenes `party run` knows."""
    from .scenes import SCENES

    for name, entry in SCENES.items():
        out.print(f"[bold]{name}[/]  {entry.description}")


@app.command("fabrics")
def fabrics_command() -> None:
    """List the fabric library with its key figures and sources."""
    from .fabric import library

    for name, f in library().items():
        out.print(f"[bold]{name}[/]  {f.areal_density:.3g} kg/m^2, tensile {f.tensile_warp:.4g}/{f.tensile_weft:.4g} N/m, "
                  f"shear {f.shear:.3g} N/m, bending {f.bending_rigidity:.3g} N*m — {f.description}")
        out.print(f"    source: {f.source}", highlight=False)


@app.command("run")
def run_command(
    scene: str = typer.Argument(..., help="Scene name (see `party scenes`)."),
    out_dir: Path = typer.Option(..., "--out", help="Output folder (frames/, colliders/, images/, summary.json)."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Simulated seconds."),
    spacing: Optional[float] = typer.Option(None, "--spacing", help="Node spacing of the net [m] (resolution)."),
    dt: Optional[float] = typer.Option(None, "--dt", help="Time step [s] (the paper: 1e-4)."),
    wind: Optional[float] = typer.Option(None, "--wind", help="Wind speed [m/s] (rod-wind)."),
    device: Optional[str] = typer.Option(None, "--device", help="cpu, cuda or auto (default: cuda if present)."),
    grid: Optional[int] = typer.Option(None, "--grid", help="Nodes per side of the cloth (sphere-drop)."),
    self_collision: Optional[str] = typer.Option(None, "--self-collision", help="on or off: cloth-cloth collision (sphere-drop)."),
    solver: Optional[str] = typer.Option(None, "--solver", help="explicit (the paper's, the reference) or implicit (large steps)."),
    fabric: Optional[str] = typer.Option(None, "--fabric", help="Fabric: a library name (see `party fabrics`) or a .toml/.json file."),
    quick: bool = typer.Option(False, "--quick", help="Coarse and short: a fast check (CI)."),
    resume: bool = typer.Option(False, "--resume",
                                help="Continue from OUT/checkpoint.npz (the dress: and its sewing from OUT/sewn.npz)."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Write into an --out folder that holds files party did "
                                   "not write (they are kept; only party's own are replaced)."),
) -> None:
    """Run a scene and write its frames, images and summary.json."""
    from dataclasses import fields

    from .device import resolve
    from .fabric import fabric_by_name
    from .launch import thread_count
    from .output.folder import check_output_path, open_output
    from .scenes import scene_by_name
    from .scenes.runner import run_scene
    from .solvers.registry import check_solver

    entry = scene_by_name(scene)
    check_output_path(out_dir)
    thread_count()
    resolve(device)
    if self_collision is not None and self_collision not in ("on", "off"):
        raise InvalidInput(f"--self-collision must be on or off, got {self_collision!r}")
    options = {"duration": duration, "spacing": spacing, "dt": dt, "wind_speed": wind, "grid": grid,
               "self_collision": None if self_collision is None else self_collision == "on",
               "solver": None if solver is None else check_solver(solver),
               "fabric": None if fabric is None else fabric_by_name(fabric), "quick": quick or None}
    accepted = {f.name for f in fields(entry.settings)}
    flags = {"wind_speed": "wind", "self_collision": "self-collision"}
    for name, value in options.items():
        if value is not None and name not in accepted:
            raise InvalidInput(f"scene {scene!r} has no option --{flags.get(name, name)}")
    settings = entry.settings(**{k: v for k, v in options.items() if v is not None})
    _say_if_nothing_to_resume(resume, out_dir, "the run starts from its first frame")
    with open_output(out_dir, "run", overwrite=overwrite, description=scene) as folder:
        built = entry.build(settings, device=device, out=folder.path, resume=resume, progress=progress)
        summary = run_scene(built, folder.path, resume=resume, progress=progress, folder=folder)
    out.print(f"{scene}: {summary['nodes']} nodes, {summary['steps']} steps, {summary['simulated_seconds']:.3f} s "
              f"simulated in {summary['wall_seconds']:.1f} s; max elongation {summary['max_elongation']:.4f}, "
              f"body penetrations {summary['body_penetrations']}, cloth crossings {summary['cloth_crossings']}")
    out.print(f"results in {out_dir}/")


def _say_if_nothing_to_resume(resume: bool, out_dir: Path, instead: str) -> None:
    """With ``--resume``, say so where ``out_dir`` holds no checkpoint to go on from."""
    if resume and not (out_dir / "checkpoint.npz").exists():
        out.print(f"[yellow]nothing to resume: no checkpoint.npz in {out_dir}; {instead}[/]", highlight=False)


@app.command("drape")
def drape_command(
    pattern: Path = typer.Argument(..., help="Pattern file: our JSON, GarmentCode JSON or DXF-AAMA (.dxf)."),
    body: str = typer.Option("M", "--body", help="Body: a dress-form size (S, M, L) or a mesh file (OBJ/PLY/STL/glTF)."),
    fabric: str = typer.Option("wool_flannel", "--fabric", help="Fabric: a library name (see `party fabrics`) or a .toml/.json file."),
    solver: str = typer.Option("explicit", "--solver", help="explicit (the paper's relaxation) or implicit (large steps)."),
    out_dir: Path = typer.Option(..., "--out", help="Output folder (garment.obj/.glb, body.obj, images/, summary.json)."),
    spacing_mm: float = typer.Option(20.0, "--spacing-mm", help="Node spacing of the net [mm] (resolution)."),
    units: Optional[str] = typer.Option(None, "--units", help="Units of a DXF pattern (m, cm, mm, in) if its header has none."),
    body_units: Optional[str] = typer.Option(None, "--body-units", help="Units of the body mesh (default: detected from its height)."),
    up: Optional[str] = typer.Option(None, "--up", help="Up axis of the body mesh: x, y or z (default: its longest extent)."),
    seams: Optional[Path] = typer.Option(None, "--seams", help="Seams side file for a DXF pattern (default: PATTERN.seams.json)."),
    device: Optional[str] = typer.Option(None, "--device", help="cpu, cuda or auto."),
    images: bool = typer.Option(True, "--images/--no-images", help="Render front, side and back views."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show progress bars."),
    resume: bool = typer.Option(False, "--resume",
                                help="Go on from OUT/checkpoint.npz (the sewing's last stage done, or the draping)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Write into an --out folder that holds files party did "
                                   "not write (they are kept; only party's own are replaced)."),
    time_limit: float = typer.Option(600.0, "--time-limit", help="Wall seconds the drape may take: past them it "
                                     "stops, keeps its result and checkpoint, and fails its quality gate."),
) -> None:
    """Sew a pattern onto a body and drape it under gravity."""
    from .device import resolve
    from .fabric import fabric_by_name
    from .launch import thread_count
    from .output.folder import check_output_path
    from .scenes.drape import DrapeSettings, drape
    from .solvers.registry import check_solver

    if not (spacing_mm > 0):
        raise InvalidInput(f"--spacing-mm must be positive, got {spacing_mm}")
    check_output_path(out_dir)
    thread_count()
    resolve(device)
    the_fabric = fabric_by_name(fabric)
    _say_if_nothing_to_resume(resume, out_dir, "the drape starts from the beginning")
    summary = drape(pattern, body, the_fabric, out_dir,
                    DrapeSettings(spacing=spacing_mm / 1000.0, solver=check_solver(solver), device=device,
                                  pattern_units=units, seams_file=seams, body_units=body_units, up=up, images=images,
                                  progress=progress, resume=resume, overwrite=overwrite, time_limit=time_limit))
    out.print(f"{pattern.name}: {summary['nodes']} nodes, {summary['seams']} seams (max gap "
              f"{summary['max_seam_gap_mm']:.2f} mm), body penetrations {summary['body_penetrations']} "
              f"(body vertices through the cloth {summary['body_vertices_through_cloth']}), "
              f"cloth crossings {summary['cloth_crossings']}, {summary['wall_seconds']:.0f} s")
    if summary["max_sewn_elongation"] > 1.0 + the_fabric.strain_limit + 1e-3:
        out.print(f"[yellow]tight: sewn up to {summary['max_sewn_elongation']:.2f} times rest length, beyond "
                  f"{the_fabric.name}'s limit of {1.0 + the_fabric.strain_limit:.2f}, where the pattern is smaller "
                  "than this body or its sewing had not settled; the cloth keeps that stretch[/]")
    if summary["elements_beyond_limit"]:
        out.print(f"[yellow]stretched: {summary['elements_beyond_limit']} elements ended more than 2 % beyond their "
                  f"plastic limit (up to {summary['max_elongation']:.2f} times rest length), held there by the "
                  "collision response or the crossing guard[/]")
    if summary["max_seam_gap_mm"] > OPEN_SEAM_MM:
        seam, gap = max(summary["seam_gaps_mm"].items(), key=lambda item: item[1])
        out.print(f"[yellow]open seam: {seam} was still {gap:.1f} mm apart when the sewing stopped, and the garment "
                  "was joined across it[/]", highlight=False)
    relaxation = summary["relaxation"]
    out.print(f"draped: at rest after {relaxation['draping_steps']} steps" if relaxation["at_rest"] else
              f"[yellow]draped: still moving after {relaxation['draping_steps']} steps[/]")
    out.print(f"results in {out_dir}/")
    if not summary["quality"]["passed"]:
        err.print(f"[bold yellow]warning:[/] the drape missed its quality gates: {'; '.join(summary['quality']['reasons'])}",
                  highlight=False, soft_wrap=True)


@app.command("batch")
def batch_command(
    patterns: list[str] = typer.Argument(..., help="Pattern files, folders or globs (any format `party drape` reads)."),
    bodies: str = typer.Option("M", "--bodies", help="Bodies, comma-separated: dress-form sizes or mesh files."),
    fabrics: str = typer.Option("wool_flannel", "--fabrics", help="Fabrics, comma-separated: library names or files."),
    out_dir: Path = typer.Option(..., "--out", help="Dataset folder (one folder per item, manifest.parquet, "
                                 "contact_sheet.png, logs/)."),
    workers: Optional[int] = typer.Option(None, "--workers", help="Items draped at once (default: one per core)."),
    ray: Optional[str] = typer.Option(None, "--ray", help="Run the items as Ray tasks on the cluster at ADDRESS, or "
                                      "'auto' (the running cluster, else a local one)."),
    time_limit: float = typer.Option(600.0, "--time-limit", help="Wall seconds each drape may take."),
    spacing_mm: float = typer.Option(20.0, "--spacing-mm", help="Node spacing of the net [mm]."),
    solver: str = typer.Option("explicit", "--solver", help="explicit or implicit."),
    device: Optional[str] = typer.Option(None, "--device", help="cpu, cuda or auto."),
    resume: bool = typer.Option(False, "--resume", help="Skip the items the manifest holds; go on with the others."),
    images: bool = typer.Option(True, "--images/--no-images", help="Render each item's views (and the contact sheet)."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Write into an --out folder that holds files party did "
                                   "not write (they are kept; only party's own are replaced)."),
) -> None:
    """Drape every pattern on every body in every fabric into a dataset, unattended."""
    from .batch import BatchSettings, plan, run_batch
    from rich.table import Table

    from .batch.report import contact_sheet, tally
    from .batch.worker import ItemOptions
    from .body.load import load_body
    from .fabric import fabric_by_name
    from .output.folder import check_output_path, open_output
    from .solvers.registry import check_solver

    if not (spacing_mm > 0):
        raise InvalidInput(f"--spacing-mm must be positive, got {spacing_mm}")
    check_output_path(out_dir)
    items = plan(patterns, [b.strip() for b in bodies.split(",")], [f.strip() for f in fabrics.split(",")])
    for name in dict.fromkeys(i.fabric for i in items):
        fabric_by_name(name)
    for name in dict.fromkeys(i.body for i in items):
        load_body(name)
    settings = BatchSettings(workers=workers, ray=ray, resume=resume,
                             item=ItemOptions(spacing_mm=spacing_mm, solver=check_solver(solver), time_limit=time_limit,
                                              images=images, device=device))
    with open_output(out_dir, "batch", overwrite=overwrite, description=f"{len(items)} items") as folder:
        with _batch_progress(progress) as (on_start, on_done):
            manifest = run_batch(items, folder.path, settings, on_start=on_start, on_done=on_done)
        rows = list(manifest.rows.values())
        if images and rows:
            contact_sheet(folder.path / "contact_sheet.png", folder.path, rows)
    statuses, reasons = tally(rows)
    table = Table()
    table.add_column("status")
    table.add_column("items", justify="right")
    for status in ("passed", "failed", "timeout", "error"):
        table.add_row(status, str(statuses[status]))
    out.print(table)
    out.print(f"{statuses['passed']} of {len(rows)} items passed ({100.0 * statuses['passed'] / max(len(rows), 1):.0f} %)"
              + (f"; reasons of the {len(rows) - statuses['passed']} that did not:" if reasons else ""), highlight=False)
    for reason, count in reasons.most_common():
        out.print(f"  {count:4d}  {reason}", highlight=False)
    out.print(f"results in {out_dir}/ (manifest.parquet{', contact_sheet.png' if images and rows else ''})")


@contextmanager
def _batch_progress(shown: bool):
    """(on_start, on_done) for :func:`party.batch.run_batch`: a progress bar of items done,
    passed and failed with the time left, and a line for each item that did not pass."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    counts = {"passed": 0, "failed": 0}
    bar = Progress(TextColumn("batch"), BarColumn(), MofNCompleteColumn(), TextColumn("{task.fields[tally]}"),
                   TimeRemainingColumn(), console=out, disable=not shown)
    task = None

    def on_start(total: int, done: int) -> None:
        nonlocal task
        if done:
            out.print(f"resuming: skipping {done} items already in the manifest")
        task = bar.add_task("batch", total=total, completed=done, tally="")

    def on_done(item, row: dict) -> None:
        counts["passed" if row["status"] == "passed" else "failed"] += 1
        if row["status"] != "passed":
            bar.console.print(f"{item.name}: {row['status']}: {'; '.join(row['reasons'] or [])}", highlight=False,
                              soft_wrap=True)
        bar.update(task, advance=1, tally=f"passed {counts['passed']}, not {counts['failed']}")

    with bar:
        yield on_start, on_done


@app.command("validate")
def validate_command(
    case: Optional[str] = typer.Option(None, "--case", help="One case (default: all): oscillation, catenary, cantilever, "
                                       "friction, restitution, cusick, cusick-measured, convergence."),
    fabric: Optional[str] = typer.Option(None, "--fabric", help="Fabric: a library name or a .toml/.json file "
                                         "(default: cotton; Cusick: every library fabric)."),
    solver: str = typer.Option("explicit", "--solver", help="explicit (the paper's, the reference) or implicit."),
    out_dir: Path = typer.Option(Path("out/validate"), "--out", help="Output folder (results.json and PNG plots)."),
    quick: bool = typer.Option(False, "--quick", help="Coarse resolutions: the CI's run."),
    resume: bool = typer.Option(False, "--resume", help="Keep the cases OUT/results.json holds for the same fabric, "
                                "solver and resolution; run the rest."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Write into an --out folder that holds files party did "
                                   "not write (they are kept; only party's own are replaced)."),
) -> None:
    """Run the validation cases and print each quantity against its reference; exit status 1
    when any misses its tolerance. results.json is written after each case."""
    from .fabric import fabric_by_name
    from .launch import thread_count
    from .output.folder import check_output_path, open_output
    from .solvers.registry import check_solver
    from .validate import case_names, run_validation
    from .validate.report import print_table, read_results, write_results

    names = case_names(case)
    chosen = None if fabric is None else fabric_by_name(fabric)
    check_solver(solver)
    check_output_path(out_dir)
    thread_count()
    settings = {"fabric": fabric, "fabric_properties": None if chosen is None else chosen.to_dict(), "solver": solver,
                "quick": quick}
    with open_output(out_dir, "validate", overwrite=overwrite, description=case or "all cases") as folder:
        path = folder.path / "results.json"
        kept = read_results(path, settings, warn=lambda line: err.print(f"[yellow]{line}[/]", highlight=False,
                                                                        soft_wrap=True)) \
            if resume else {}
        with out.status("validating") as status:
            results = run_validation(names, chosen, solver, folder.path, quick=quick, kept=kept,
                                     on_case=lambda name: status.update(f"validating: {name}"),
                                     on_result=lambda done: write_results(done, path, settings, complete=False))
        print_table(results, out)
        write_results(results, path, settings)
    failed = [c for r in results for c in r.checks if not c.passed]
    out.print(f"{sum(len(r.checks) for r in results) - len(failed)} of {sum(len(r.checks) for r in results)} checks "
              f"passed; results in {out_dir}/results.json")
    if failed:
        raise typer.Exit(1)


def main() -> None:
    """Entry point: user errors become one line on stderr and exit status 1; so does any other
    failure (out of memory, a full disk, a bug), whose traceback goes to a file the line names
    (``PARTY_TRACEBACK=1`` shows it instead)."""
    try:
        status = app(standalone_mode=False)
    except PartyError as exc:
        err.print(f"[bold red]error:[/] {exc}", highlight=False, soft_wrap=True)
        raise SystemExit(1)
    except (typer.Abort, KeyboardInterrupt):
        status = INTERRUPTED
    except MemoryError:
        err.print("[bold red]error:[/] out of memory; try a coarser --spacing-mm (or --grid) or close other programs",
                  highlight=False, soft_wrap=True)
        raise SystemExit(1)
    except Exception as exc:
        if _is_usage_error(exc):
            exc.show()
            raise SystemExit(exc.exit_code)
        if os.environ.get("PARTY_TRACEBACK"):
            raise
        err.print(f"[bold red]error:[/] {_unexpected(exc)}", highlight=False, soft_wrap=True)
        raise SystemExit(1)
    if status == INTERRUPTED:  # typer also turns Ctrl-C into Exit(130) itself
        err.print("interrupted; rerun with --resume to continue")
    if isinstance(status, int) and status:
        raise SystemExit(status)


def _unexpected(exc: Exception) -> str:
    """One line for a failure that is not a :class:`PartyError`: what the system said where it
    is the system's (a full disk, a folder that went away), else a bug's name and the file its
    traceback was written to."""
    if isinstance(exc, OSError) and exc.strerror:
        where = f" ({exc.filename})" if exc.filename else ""
        return f"{exc.strerror}{where}"
    import tempfile
    import traceback

    path = Path(tempfile.gettempdir()) / f"party-traceback-{os.getpid()}.txt"
    path.write_text("".join(traceback.format_exception(exc)))
    first = (str(exc).splitlines() or [""])[0][:200]
    return (f"internal error ({type(exc).__name__}: {first}); this is a bug in party, please report it with "
            f"the traceback in {path}")


def _is_usage_error(exc: Exception) -> bool:
    """Whether ``exc`` is click's usage error (an unknown option, a missing argument), which
    shows itself as a usage line: click's ``ClickException``, which typer 0.2x vendors as
    ``typer._click``, so it is recognised by what it has rather than imported."""
    return callable(getattr(exc, "show", None)) and isinstance(getattr(exc, "exit_code", None), int)


if __name__ == "__main__":
    main()
