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
    panels = {}
    for name, p in spec["panels"].items():
        where = f"{source}: panel {name!r}"
        try:
            verts = np.asarray(p["vertices"], float) * scale
            raw_edges = p["edges"]
        except (KeyError, TypeError, ValueError) as exc:
            raise InvalidInput(f"{where}: missing or malformed vertices/edges ({exc})") from None
        if verts.ndim != 2 or verts.shape[1] != 2:
            raise InvalidInput(f"{where}: vertices must be 2-D points")
        edges = []
        for k, e in enumerate(raw_edges):
            try:
                i, j = e["endpoints"]
                a, b = verts[i], verts[j]
            except (KeyError, ValueError, IndexError, TypeError):
                raise InvalidInput(f"{where} edge {k}: endpoints missing or out of range") from None
            edges.append(_edge(a, b, e.get("curvature"), scale, e.get("label", ""), f"{where} edge {k}"))
        translation = np.asarray(p.get("translation", [0, 0, 0]), float) * scale
        rotation = euler_xyz_degrees(p.get("rotation", [0, 0, 0]))
        placement = Placement(translation=Y_UP_TO_Z_UP @ translation, rotation=Y_UP_TO_Z_UP @ rotation)
        panels[name] = Panel(name, tuple(edges), np.array([1.0, 0.0]), None, "shoulder", placement)
    seams = []
    for k, st in enumerate(spec.get("stitches", [])):
        try:
            a, b = (EdgeRef(s["panel"], int(s["edge"])) for s in st[:2])
        except (KeyError, TypeError, ValueError):
            raise InvalidInput(f"{source}: stitch {k} is malformed (expected two {{panel, edge}} entries)") from None
        seams.append(Seam(a, b, same_direction=len(st) == 3 and st[2] == "right_wrong"))
    return Pattern(source.rsplit("/", 1)[-1].removesuffix(".json"), panels, tuple(seams))


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
