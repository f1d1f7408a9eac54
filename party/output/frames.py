"""Mesh frames on disk (PLY, metres) and run checkpoints."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import trimesh

from ..errors import InvalidInput


def frame_path(out: Path, index: int) -> Path:
    """``out/frames/frame_000123.ply``: names sort in time order."""
    return out / "frames" / f"frame_{index:06d}.ply"


def write_mesh(path: Path, points: np.ndarray, faces: np.ndarray, uv: np.ndarray | None = None) -> None:
    """Write a triangle mesh [m] atomically (PLY or OBJ by suffix)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    visual = trimesh.visual.TextureVisuals(uv=uv) if uv is not None and path.suffix == ".obj" else None
    mesh = trimesh.Trimesh(points, faces, process=False, visual=visual)
    tmp = path.with_name(path.name + ".part")
    data = mesh.export(file_type=path.suffix[1:])
    tmp.write_bytes(data.encode() if isinstance(data, str) else data)
    os.replace(tmp, path)


def write_json(path: Path, data: dict, default=None) -> None:
    """Write ``data`` as JSON atomically; ``default`` as :func:`json.dumps` takes it."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".part")
    tmp.write_text(json.dumps(data, indent=2, sort_keys=False, default=default) + "\n")
    os.replace(tmp, path)


def save_checkpoint(path: Path, **arrays) -> None:
    """Save the arrays needed to resume a run, atomically."""
    tmp = path.with_name(path.name + ".part.npz")
    np.savez(tmp, **arrays)
    os.replace(tmp, path)


def load_checkpoint(path: Path) -> dict:
    """The arrays :func:`save_checkpoint` saved at ``path``; :class:`InvalidInput` where the file
    is damaged (cut short by a full disk, say) or not a checkpoint at all."""
    import zipfile

    try:
        with np.load(path, allow_pickle=False) as data:
            return {k: data[k] for k in data.files}
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as error:
        reason = "not a NumPy archive" if isinstance(error, (zipfile.BadZipFile, ValueError)) else type(error).__name__
        raise InvalidInput(f"{path} is damaged or not a party checkpoint ({reason}); remove it or drop --resume") \
            from None
