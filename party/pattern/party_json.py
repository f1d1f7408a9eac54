"""Our own pattern format: JSON checked against ``pattern.schema.json`` (lengths in the file's
``units``, converted to metres here)."""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path

import numpy as np

from ..errors import InvalidInput
from ..units import length_unit
from .edges import Edge, arc_through_radius, bezier, line
from .pattern import EdgeRef, Panel, Pattern, Placement, Seam, euler_xyz_degrees


def schema() -> dict:
    """The JSON Schema of the format."""
    return json.loads(resources.files(__package__).joinpath("pattern.schema.json").read_text())


def validate_document(doc: dict, source: str) -> None:
    """Raise a one-line :class:`InvalidInput` at the first schema violation."""
    import jsonschema

    validator = jsonschema.Draft202012Validator(schema())
    errors = sorted(validator.iter_errors(doc), key=lambda e: list(e.absolute_path))
    if errors:
        e = errors[0]
        where = "/".join(str(p) for p in e.absolute_path) or "(top level)"
        message = e.message if len(e.message) < 160 else e.message[:157] + "..."
        raise InvalidInput(f"{source}: invalid pattern at {where}: {message}")


def pattern_from_document(doc: dict, source: str = "pattern") -> Pattern:
    """Build a :class:`Pattern` from a parsed document of our format."""
    validate_document(doc, source)
    scale = length_unit(doc["units"])
    panels = {}
    for name, spec in doc["panels"].items():
        verts = np.asarray(spec["vertices"], float) * scale
        edges = []
        for k, e in enumerate(spec["edges"]):
            i, j = e["endpoints"]
            if i >= len(verts) or j >= len(verts):
                raise InvalidInput(f"{source}: panel {name!r} edge {k} names vertex {max(i, j)}, "
                                   f"but the panel has {len(verts)} vertices")
            edges.append(_edge(verts[i], verts[j], e.get("curve", {"type": "line"}), scale, e.get("name", "")))
        placement = None
        if "placement" in spec:
            p = spec["placement"]
            placement = Placement(
                translation=np.asarray(p.get("translation", [0, 0, 0]), float) * scale,
                rotation=euler_xyz_degrees(p.get("rotation", [0, 0, 0])),
                wrap_radius=p["wrap_radius"] * scale if "wrap_radius" in p else None,
                wrap_axis=tuple(np.asarray(p.get("wrap_axis", [0, 0]), float) * scale),
            )
        panels[name] = Panel(name, tuple(edges), np.asarray(spec["grain"], float), spec.get("part"),
                             spec.get("anchor", "shoulder"), placement, spec.get("label", ""))
    panels, refs = _split_ranges(panels, doc["seams"], source)
    seams = tuple(Seam(refs[2 * k], refs[2 * k + 1], bool(s.get("same_direction", False)))
                  for k, s in enumerate(doc["seams"]))
    return Pattern(doc.get("name", Path(source).stem), panels, seams)


def _edge(a: np.ndarray, b: np.ndarray, curve: dict, scale: float, name: str) -> Edge:
    kind = curve["type"]
    if kind == "line":
        return line(a, b, name)
    if kind == "arc":
        return arc_through_radius(a, b, curve["radius"] * scale, large_arc=curve.get("large_arc", False),
                                  ccw=curve.get("ccw", True), name=name)
    return bezier(a, np.asarray(curve["control"], float) * scale, b, name)


def _split_ranges(panels: dict[str, Panel], seams: list[dict], source: str):
    """Cut edges where a seam sews only part of them, so that every seam joins whole edges.
    Returns the new panels and one :class:`EdgeRef` per seam side (a, b, a, b, ...)."""
    sides = [s[k] for s in seams for k in ("a", "b")]
    cuts: dict[tuple[str, int], set[float]] = {}
    resolved = []
    for side in sides:
        name = side["panel"]
        if name not in panels:
            raise InvalidInput(f"{source}: seam names unknown panel {name!r}")
        k = panels[name].edge_index(side["edge"])
        lo, hi = side.get("range", [0.0, 1.0])
        if not 0.0 <= lo < hi <= 1.0:
            raise InvalidInput(f"{source}: seam range {[lo, hi]} on {name}.edge[{k}] must rise within [0, 1]")
        cuts.setdefault((name, k), {0.0, 1.0}).update((lo, hi))
        resolved.append((name, k, lo, hi))
    new_index: dict[tuple[str, int, float], int] = {}
    for name, panel in list(panels.items()):
        edges: list[Edge] = []
        for k, edge in enumerate(panel.edges):
            points = sorted(cuts.get((name, k), {0.0, 1.0}))
            rest, done = edge, 0.0
            for lo, hi in zip(points[:-1], points[1:]):
                new_index[(name, k, lo)] = len(edges)
                if hi < 1.0:
                    piece, rest = rest.split((hi - done) / (1.0 - done))
                    done = hi
                else:
                    piece = rest
                edges.append(piece)
        panels[name] = Panel(name, tuple(edges), panel.grain, panel.part, panel.anchor, panel.placement, panel.label)
    refs = []
    for name, k, lo, hi in resolved:
        points = sorted(cuts[(name, k)])
        if points[points.index(lo) + 1] != hi:
            raise InvalidInput(f"{source}: seam ranges on {name}.edge[{k}] overlap")
        refs.append(EdgeRef(name, new_index[(name, k, lo)]))
    return panels, refs

