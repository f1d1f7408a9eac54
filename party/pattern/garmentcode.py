"""Import of GarmentCode's pattern specification JSON (Korosteleva and Sorkine-Hornung 2023).

The format: ``pattern.panels`` maps names to 2-D ``vertices``, ``edges`` (``endpoints``, an
optional ``curvature`` and ``label``), ``translation`` and ``rotation`` (XYZ Euler degrees);
``pattern.stitches`` pairs ``{panel, edge}`` sides, with an optional third entry
``"right_wrong"``; lengths are in units of 1/``properties.units_in_meter`` m, the body frame is
Y up. Curvature: ``quadratic``/``cubic`` control points relative to the edge (fraction along
it, fraction of its length to the left), ``circle`` with [radius, large_arc, right]. Panels are
cut with the warp along their local x axis (GarmentCode stores no grain line).
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInput
from .edges import Edge, arc_through_radius, bezier, line
from .pattern import EdgeRef, Panel, Pattern, Placement, Seam, euler_xyz_degrees

Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
"""Rotation taking a Y-up frame (x right, y up, z to the front) to ours (x right, y to the
back, z up): (x, y, z) -> (x, -z, y)."""


def is_garmentcode(doc: dict) -> bool:
    return isinstance(doc, dict) and isinstance(doc.get("pattern"), dict) and "panels" in doc["pattern"]


def pattern_from_garmentcode(doc: dict, source: str = "pattern") -> Pattern:
    """Build a :class:`Pattern` (metres, Z up) from a GarmentCode specification."""
    spec = doc["pattern"]
    units = doc.get("properties", {}).get("units_in_meter")
    if not isinstance(units, (int, float)) or not units > 0:
        raise InvalidInput(f"{source}: properties.units_in_meter must be a positive number, got {units!r}")
    if doc.get("properties", {}).get("curvature_coords", "relative") != "relative":
        raise InvalidInput(f"{source}: only relative curvature coordinates are supported")
    scale = 1.0 / units
    if not isinstance(spec["panels"], dict):
        raise InvalidInput(f"{source}: pattern.panels must be a table of panels by name, got a "
                           f"{type(spec['panels']).__name__}")
    panels = {}
    for name, p in spec["panels"].items():
        where = f"{source}: panel {name!r}"
        if not isinstance(p, dict):
            raise InvalidInput(f"{where} must be a table (vertices, edges, translation, rotation), got "
                               f"{type(p).__name__}")
        verts = _numbers(p.get("vertices"), f"{where}: vertices", (-1, 2)) * scale
        raw_edges = p.get("edges")
        if not isinstance(raw_edges, list) or not raw_edges:
            raise InvalidInput(f"{where}: edges must be a list of edges")
        bad = np.flatnonzero(~np.isfinite(verts).all(axis=1))
        if len(bad):
            shown = ", ".join(f"{x:g}" for x in verts[bad[0]] / scale)
            raise InvalidInput(f"{where}: vertex {bad[0]} is not a finite number ([{shown}]); fix the file's vertices")
        edges = []
        for k, e in enumerate(raw_edges):
            try:
                i, j = e["endpoints"]
                if isinstance(i, bool) or isinstance(j, bool) or min(int(i), int(j)) < 0:
                    raise IndexError
                a, b = verts[int(i)], verts[int(j)]
            except (KeyError, ValueError, IndexError, TypeError):
                raise InvalidInput(f"{where} edge {k}: endpoints missing or out of range") from None
            try:
                edges.append(_edge(a, b, e.get("curvature"), scale, e.get("label", ""), f"{where} edge {k}"))
            except InvalidInput:
                raise
            except (TypeError, ValueError, KeyError, IndexError, AttributeError) as exc:
                raise InvalidInput(f"{where} edge {k}: malformed curvature ({type(exc).__name__}: {exc})"[:300]) \
                    from None
        translation = _numbers(p.get("translation", [0, 0, 0]), f"{where}: translation", (3,)) * scale
        rotation = euler_xyz_degrees(_numbers(p.get("rotation", [0, 0, 0]), f"{where}: rotation (degrees)", (3,)))
        placement = Placement(translation=Y_UP_TO_Z_UP @ translation, rotation=Y_UP_TO_Z_UP @ rotation)
        label = p.get("label", "")
        panels[name] = Panel(name, tuple(edges), np.array([1.0, 0.0]), None, "shoulder", placement,
                             label if isinstance(label, str) else "")
    seams = []
    stitches = spec.get("stitches", [])
    if not isinstance(stitches, list):
        raise InvalidInput(f"{source}: pattern.stitches must be a list of stitches")
    for k, st in enumerate(stitches):
        try:
            a, b = (EdgeRef(s["panel"], _index(s["edge"])) for s in st[:2])
        except (KeyError, TypeError, ValueError):
            raise InvalidInput(f"{source}: stitch {k} is malformed (expected two {{panel, edge}} entries)") from None
        seams.append(Seam(a, b, same_direction=len(st) == 3 and st[2] == "right_wrong"))
    return Pattern(source.rsplit("/", 1)[-1].removesuffix(".json"), panels, tuple(seams))


def _numbers(value, what: str, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` as a float array of ``shape`` (-1: any length), or :class:`InvalidInput` saying
    what it should be."""
    expected = "a list of [x, y] points" if shape == (-1, 2) else f"{shape[0]} numbers"
    try:
        if any(isinstance(x, (str, bool)) for x in np.ravel(np.asarray(value, dtype=object))):
            raise ValueError
        array = np.asarray(value, float)
    except (TypeError, ValueError):
        raise InvalidInput(f"{what} must be {expected}, got {value!r}"[:300]) from None
    if array.ndim != len(shape) or any(want not in (-1, got) for want, got in zip(shape, array.shape)) or not array.size:
        raise InvalidInput(f"{what} must be {expected}, got {value!r}"[:300])
    return array


def _index(value) -> int:
    """An edge index given as a whole number (or its digits as a string)."""
    if isinstance(value, bool) or (isinstance(value, float) and not value.is_integer()):
        raise ValueError(value)
    return int(value)


def _edge(a: np.ndarray, b: np.ndarray, curvature, scale: float, label: str, where: str) -> Edge:
    if curvature is None:
        return line(a, b, label)
    if isinstance(curvature, list):  # old GarmentCode files: a bare quadratic control point
        curvature = {"type": "quadratic", "params": [curvature]}
    kind, params = curvature.get("type"), curvature.get("params")
    if kind in ("quadratic", "cubic"):
        rel = np.asarray(params, float).reshape(-1, 2)
        chord = b - a
        left = np.array([-chord[1], chord[0]])
        controls = a + rel[:, :1] * chord + rel[:, 1:] * left
        return bezier(a, controls, b, label)
    if kind == "circle":
        radius, large_arc, right = params
        return arc_through_radius(a, b, float(radius) * scale, large_arc=bool(large_arc), ccw=bool(right), name=label)
    raise InvalidInput(f"{where}: unknown curvature type {kind!r}")
