"""Pictures of cloth and colliders, drawn with matplotlib's 3-D axes (Agg, headless)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

LIGHT = np.array([0.4, -0.6, 0.7]) / np.linalg.norm([0.4, -0.6, 0.7])


def _shaded(points: np.ndarray, faces: np.ndarray, rgb, two_sided: bool) -> np.ndarray:
    tri = points[faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    lam = n @ LIGHT
    lam = np.abs(lam) if two_sided else np.clip(lam, 0, 1)
    shade = 0.35 + 0.65 * lam
    return np.clip(np.asarray(rgb)[None, :] * shade[:, None], 0, 1)


def draw(ax, cloth_points: np.ndarray, cloth_faces: np.ndarray, colliders=(), *, wireframe: bool = False,
         bounds: tuple[np.ndarray, np.ndarray] | None = None, elev: float = 15.0, azim: float = -60.0) -> None:
    """Draw one state on a 3-D axes: the cloth shaded (or as wireframe) and colliders in grey."""
    for c in colliders:
        ax.add_collection3d(Poly3DCollection(c.vertices[c.faces], facecolors=_shaded(c.vertices, c.faces, (0.75, 0.75, 0.78), False),
                                             edgecolors="none"))
    tri = cloth_points[cloth_faces]
    if wireframe:
        ax.add_collection3d(Poly3DCollection(tri, facecolors=(1, 1, 1, 0), edgecolors=(0.15, 0.25, 0.6, 0.8), linewidths=0.3))
    else:
        ax.add_collection3d(Poly3DCollection(tri, facecolors=_shaded(cloth_points, cloth_faces, (0.80, 0.25, 0.22), True),
                                             edgecolors="none"))
    lo, hi = bounds if bounds is not None else (cloth_points.min(0), cloth_points.max(0))
    center, half = (lo + hi) / 2, (hi - lo).max() / 2 * 1.05
    ax.set_xlim(center[0] - half, center[0] + half)
    ax.set_ylim(center[1] - half, center[1] + half)
    ax.set_zlim(center[2] - half, center[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()


def render_frame(path: Path, cloth_points: np.ndarray, cloth_faces: np.ndarray, colliders=(), *, title: str = "",
                 size_px: int = 800, **view) -> None:
    """One PNG of one state."""
    fig = plt.figure(figsize=(size_px / 100, size_px / 100), dpi=100)
    ax = fig.add_subplot(projection="3d")
    draw(ax, cloth_points, cloth_faces, colliders, **view)
    if title:
        ax.set_title(title)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)


def render_sequence(path: Path, frames: list[tuple[str, np.ndarray]], cloth_faces: np.ndarray, colliders=(), *,
                    columns: int = 4, panel_px: int = 360, **view) -> None:
    """A grid of panels, one per (label, points) frame, sharing one view box."""
    allp = np.concatenate([p for _, p in frames])
    bounds = (allp.min(0), allp.max(0))
    rows = int(np.ceil(len(frames) / columns))
    fig = plt.figure(figsize=(columns * panel_px / 100, rows * panel_px / 100), dpi=100)
    for k, (label, pts) in enumerate(frames):
        ax = fig.add_subplot(rows, columns, k + 1, projection="3d")
        draw(ax, pts, cloth_faces, colliders, bounds=bounds, **view)
        ax.set_title(label, fontsize=9)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)
