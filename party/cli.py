"""The ``party`` command."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer
from rich.console import Console

from .errors import PartyError

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="PARTY dress simulator: the paper's experiments and garment draping.")
err = Console(stderr=True)
out = Console()


@app.command("scenes")
def scenes_command() -> None:
    """List the scenes `party run` knows."""
    from .scenes import SCENES

    for name, (_, description) in SCENES.items():
        out.print(f"[bold]{name}[/]  {description}")


@app.command("run")
def run_command(
    scene: str = typer.Argument(..., help="Scene name (see `party scenes`)."),
    out_dir: Path = typer.Option(..., "--out", help="Output folder (frames/, colliders/, images/, summary.json)."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Simulated seconds."),
    spacing: Optional[float] = typer.Option(None, "--spacing", help="Node spacing of the net [m] (resolution)."),
    dt: Optional[float] = typer.Option(None, "--dt", help="Time step [s] (the paper: 1e-4)."),
    wind: Optional[float] = typer.Option(None, "--wind", help="Wind speed [m/s] (rod-wind)."),
    device: Optional[str] = typer.Option(None, "--device", help="cpu, cuda or auto (default: cuda if present)."),
    resume: bool = typer.Option(False, "--resume", help="Continue from OUT/checkpoint.npz."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar."),
) -> None:
    """Run a scene and write its frames, images and summary.json."""
    from .scenes import scene_by_name
    from .scenes.runner import run_scene

    options = {"duration": duration, "spacing": spacing, "dt": dt, "wind_speed": wind, "device": device}
    build = scene_by_name(scene)
    built = build(**{k: v for k, v in options.items() if v is not None})
    summary = run_scene(built, out_dir, resume=resume, progress=progress)
    out.print(f"{scene}: {summary['nodes']} nodes, {summary['steps']} steps, {summary['simulated_seconds']:.3f} s "
              f"simulated in {summary['wall_seconds']:.1f} s; max elongation {summary['max_elongation']:.4f}, "
              f"body penetrations {summary['body_penetrations']}, cloth crossings {summary['cloth_crossings']}")
    out.print(f"results in {out_dir}/")


def main() -> None:
    """Entry point: user errors become one line on stderr and exit status 1."""
    try:
        app(standalone_mode=False)
    except PartyError as exc:
        err.print(f"[bold red]error:[/] {exc}", highlight=False, soft_wrap=True)
        raise SystemExit(1)
    except (typer.Abort, KeyboardInterrupt):
        err.print("interrupted; rerun with --resume to continue")
        raise SystemExit(130)
    except Exception as exc:  # click usage errors
        import click

        if isinstance(exc, click.ClickException):
            exc.show()
            raise SystemExit(exc.exit_code)
        raise


if __name__ == "__main__":
    main()
