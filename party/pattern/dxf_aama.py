"""Import of DXF-AAMA pattern files (ASTM D6673, the AAMA/ASTM DXF exchange), read with ezdxf.

Layout read: each piece is a BLOCK holding its cut line (layer 1, a closed POLYLINE or
LWPOLYLINE), its grain line (layer 7, a LINE or two-point polyline), internal lines (layer 8)
and turn points (layer 2, POINTs at the outline's corners), with a TEXT ``Piece Name: NAME``;
the model space INSERTs the blocks. Units come from the header's $INSUNITS (or the caller).

The outline is cut into edges at the turn points (the whole outline is one edge if there are
none), numbered from the first turn point along the polyline. DXF carries no seams: they come
from a small JSON side file ``{"seams": [{"a": {"panel", "edge"}, "b": {...}}], "parts":
{"PANEL": "front", ...}, "anchors": {"PANEL": "waist"}}`` (see :func:`load_dxf_pattern`).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import InvalidInput
from ..units import length_unit
from .edges import Edge
from .pattern import EdgeRef, Panel, Pattern, Seam

INSUNITS = {1: "in", 4: "mm", 5: "cm", 6: "m"}
"""$INSUNITS codes to our unit names."""

CUT_LAYER, TURN_LAYER, GRAIN_LAYER, INTERNAL_LAYER = "1", "2", "7", "8"


def load_dxf_pattern(path: Path, *, seams_file: Path | None = None, units: str | None = None) -> Pattern:
    """Read an AAMA DXF file (and its seams side file, default ``PATH.seams.json`` if present)."""
    import ezdxf

    path = Path(path)
    try:
        doc = ezdxf.readfile(path)
    except (IOError, ezdxf.DXFStructureError) as exc:
        raise InvalidInput(f"{path}: not a readable DXF file ({exc})") from None
    if units is None:
        code = doc.header.get("$INSUNITS", 0)
        if code not in INSUNITS:
            raise InvalidInput(f"{path}: the DXF header gives no length unit ($INSUNITS={code}); pass --units")
        units = INSUNITS[code]
    scale = length_unit(units)
    side = _side_file(path, seams_file)
    parts, anchors = side.get("parts", {}), side.get("anchors", {})
    panels = {}
    for insert in doc.modelspace().query("INSERT"):
        block = doc.blocks.get(insert.dxf.name)
        panel = _piece(block, insert.dxf.name, scale, path)
        panel = Panel(panel.name, panel.edges, panel.grain, parts.get(panel.name), anchors.get(panel.name, "shoulder"))
        if panel.name in panels:
            raise InvalidInput(f"{path}: two pieces are named {panel.name!r}")
        panels[panel.name] = panel
    if not panels:
        raise InvalidInput(f"{path}: no pattern pieces (INSERTs of blocks with a layer-1 cut line) found")
    def ref(side: dict) -> EdgeRef:
        panel, edge = side["panel"], side["edge"]
        return EdgeRef(panel, panels[panel].edge_index(edge) if panel in panels else edge)

    seams = []
    for k, s in enumerate(side.get("seams", [])):
        try:
            seams.append(Seam(ref(s["a"]), ref(s["b"]), bool(s.get("same_direction", False))))
        except (KeyError, TypeError):
            raise InvalidInput(f"{path}: seam {k} of the side file needs a and b with panel and edge") from None
    return Pattern(path.stem, panels, tuple(seams))


def _side_file(path: Path, seams_file: Path | None) -> dict:
    candidate = seams_file or path.with_suffix(".seams.json")
    if not candidate.exists():
        if seams_file is not None:
            raise InvalidInput(f"{seams_file}: seams file not found")
        return {}
    try:
        return json.loads(candidate.read_text())
    except json.JSONDecodeError as exc:
        raise InvalidInput(f"{candidate}: not valid JSON ({exc.msg} at line {exc.lineno})") from None


def _xy(point) -> tuple[float, float]:
    return float(point[0]), float(point[1])


def _points(entity) -> np.ndarray:
    kind = entity.dxftype()
    if kind == "LWPOLYLINE":
        return np.asarray([p[:2] for p in entity.get_points("xy")], float)
    if kind == "POLYLINE":
        return np.asarray([_xy(v.dxf.location) for v in entity.vertices], float)
    if kind == "LINE":
        return np.asarray([_xy(entity.dxf.start), _xy(entity.dxf.end)], float)
    return np.zeros((0, 2))


def _piece(block, block_name: str, scale: float, path: Path) -> Panel:
    name, outline, grain, turns = block_name, None, None, []
    for e in block:
        layer = str(e.dxf.get("layer", "0"))
        if e.dxftype() in ("TEXT", "MTEXT"):
            text = e.dxf.text if e.dxftype() == "TEXT" else e.text
            if text.lower().startswith("piece name:"):
                name = text.split(":", 1)[1].strip()
        elif layer == CUT_LAYER and outline is None:
            outline = _points(e)
        elif layer == GRAIN_LAYER:
            grain = _points(e)
        elif layer == TURN_LAYER and e.dxftype() == "POINT":
            turns.append(np.asarray(_xy(e.dxf.location), float))
    where = f"{path}: piece {name!r}"
    if outline is None or len(outline) < 3:
        raise InvalidInput(f"{where}: no cut line (a polyline on layer 1 with at least 3 points)")
    if grain is None or len(grain) < 2:
        raise InvalidInput(f"{where}: missing grain line (layer 7)")
    outline = outline * scale
    if np.hypot(*(outline[0] - outline[-1])) < 1e-9:
        outline = outline[:-1]
    corner_ids = sorted({int(np.argmin(np.hypot(*(outline - t * scale).T))) for t in turns}) or [0]
    edges = []
    count = len(outline)
    for a, b in zip(corner_ids, corner_ids[1:] + [corner_ids[0] + count]):
        chain = outline[np.arange(a, b + 1) % count]
        kind = "line" if len(chain) == 2 else "polyline"
        edges.append(Edge(kind, chain[0], chain[-1], chain[1:-1]))
    direction = grain[-1] - grain[0]
    return Panel(name, tuple(edges), direction / max(np.hypot(*direction), 1e-12))
