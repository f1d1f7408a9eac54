"""Renders of garments on bodies with VTK (through pyvista), off screen, on a CPU.

Smooth-shaded and lit, the body in matte grey, the fabric textured through its pattern
coordinates with a woven check (one repeat every ``CHECK_SIZE`` metres of fabric, so the grain
and the seams show). Cameras follow our frame: Z up, the body facing -y.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .garment_export import split_by_panel

CHECK_SIZE = 0.04
"""Size of one check of the fabric texture [m of fabric]."""

VIEWS = {"front": (0.0, -1.0, 0.12), "side": (1.0, 0.0, 0.12), "back": (0.0, 1.0, 0.12),
         "three_quarter": (0.7, -1.0, 0.25)}
"""Camera directions (from the target towards the camera) for named views."""


def _pyvista():
    import pyvista as pv
    import vtk

    vtk.vtkObject.GlobalWarningDisplayOff()
    vtk.vtkLogger.SetStderrVerbosity(vtk.vtkLogger.VERBOSITY_OFF)
    pv.OFF_SCREEN = True
    return pv


def check_texture(size: int = 256) -> np.ndarray:
    """A two-colour woven check, RGB uint8 (size, size, 3): warp stripes along u, weft along v."""
    t = np.linspace(0.0, 1.0, size, endpoint=False)
    stripe_u = (np.sin(2 * np.pi * t) > 0.2)[None, :]
    stripe_v = (np.sin(2 * np.pi * t) > 0.2)[:, None]
    base = np.array([178, 34, 52], float)
    dark = np.array([96, 18, 40], float)
    light = np.array([235, 205, 150], float)
    img = np.broadcast_to(base, (size, size, 3)).copy()
    img[np.broadcast_to(stripe_u, (size, size))] = 0.5 * (base + dark)
    img[np.broadcast_to(stripe_v, (size, size))] = 0.5 * (base + dark)
    img[stripe_u & stripe_v] = dark
    fine = (np.arange(size) % 32 < 3)
    img[fine, :] = 0.6 * img[fine, :] + 0.4 * light
    return img.astype(np.uint8)


class GarmentRenderer:
    """A scene of a garment and colliders that can be re-posed and re-rendered.

    Args:
        triangles: Garment triangles (sewn node indices).
        triangle_panel: Panel index of each triangle.
        corner_xy: Pattern coordinates of each triangle corner [m], (t, 3, 2).
        colliders: Body and props (:class:`party.body.ColliderMesh`).
        size: Image width and height [px].
        wireframe: Draw the garment's net as lines instead of textured cloth.
    """

    def __init__(self, triangles, triangle_panel, corner_xy, colliders, *, size: int = 1024,
                 wireframe: bool = False) -> None:
        self.pv = _pyvista()
        pv = self.pv
        self.triangles, self.triangle_panel, self.corner_xy = triangles, triangle_panel, corner_xy
        self.plotter = pv.Plotter(off_screen=True, window_size=(size, size))
        self.plotter.set_background("white")
        self.plotter.enable_anti_aliasing("ssaa")
        for c in colliders:
            body = pv.PolyData(c.vertices, np.column_stack([np.full(len(c.faces), 3), c.faces]).ravel())
            self.plotter.add_mesh(body, color=(0.80, 0.80, 0.82), smooth_shading=True, specular=0.1,
                                  ambient=0.15, diffuse=0.8)
        self.wireframe = wireframe
        self.mesh = None
        self.node = None

    def pose(self, points: np.ndarray) -> None:
        """Set the garment's node positions [m]."""
        pv = self.pv
        vertices, faces, uv, node = split_by_panel(points, self.triangles, self.triangle_panel, self.corner_xy)
        if self.mesh is None:
            self.node = node
            self.mesh = pv.PolyData(vertices, np.column_stack([np.full(len(faces), 3), faces]).ravel())
            if self.wireframe:
                self.plotter.add_mesh(self.mesh, style="wireframe", color=(0.1, 0.2, 0.55), line_width=1.0)
            else:
                self.mesh.active_texture_coordinates = uv / CHECK_SIZE
                texture = pv.Texture(check_texture())
                texture.repeat = True
                self.plotter.add_mesh(self.mesh, texture=texture, smooth_shading=True, specular=0.05,
                                      ambient=0.2, diffuse=0.85)
        else:
            self.mesh.points[:] = vertices
            self.mesh.Modified()

    def render(self, path: Path, view: str = "front", *, target=None, distance: float | None = None) -> None:
        """Write a PNG seen from a named view (see :data:`VIEWS`)."""
        from PIL import Image

        img = self.image(view, target=target, distance=distance)
        path.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(img[..., :3]).save(path)

    def image(self, view: str = "front", *, target=None, distance: float | None = None) -> np.ndarray:
        """The current render as an RGB array."""
        bounds = np.array(self.plotter.bounds).reshape(3, 2)
        centre = bounds.mean(axis=1) if target is None else np.asarray(target, float)
        extent = float((bounds[:, 1] - bounds[:, 0]).max())
        direction = np.asarray(VIEWS[view], float) / np.linalg.norm(VIEWS[view])
        self.plotter.camera_position = [tuple(centre + direction * (distance or 2.2 * extent)), tuple(centre),
                                        (0.0, 0.0, 1.0)]
        self.plotter.camera.view_angle = 30.0
        self.plotter.render()
        return np.asarray(self.plotter.screenshot(return_img=True))

    def close(self) -> None:
        self.plotter.close()


def framing(points: np.ndarray, distance_factor: float) -> dict:
    """Camera keywords for :meth:`GarmentRenderer.render` and :meth:`GarmentRenderer.image` that
    look at the centre of ``points`` [m] from ``distance_factor`` times their largest extent,
    so that a series of pictures shares one camera."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    return {"target": 0.5 * (lo + hi), "distance": distance_factor * float((hi - lo).max())}


def tile(images: list[np.ndarray], labels: list[str], path: Path, columns: int = 4) -> None:
    """Put equally sized images in a labelled grid and save it as PNG."""
    from PIL import Image, ImageDraw

    h, w = images[0].shape[:2]
    rows = int(np.ceil(len(images) / columns))
    sheet = Image.new("RGB", (columns * w, rows * h), "white")
    draw = ImageDraw.Draw(sheet)
    for k, (img, label) in enumerate(zip(images, labels)):
        x, y = (k % columns) * w, (k // columns) * h
        sheet.paste(Image.fromarray(img[..., :3]), (x, y))
        draw.text((x + 10, y + 10), label, fill=(0, 0, 0))
    path.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(path)


def save_gif(images: list[np.ndarray], path: Path, seconds_per_frame: float) -> None:
    """An animated GIF of the images."""
    from PIL import Image

    frames = [Image.fromarray(img[..., :3]) for img in images]
    path.parent.mkdir(parents=True, exist_ok=True)
    frames[0].save(path, save_all=True, append_images=frames[1:], duration=int(1000 * seconds_per_frame), loop=0)
