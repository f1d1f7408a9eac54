"""Checks of a pattern against a body made before any meshing: can the panels be sewn onto this
body at all, and how many nodes will the garment have."""

from __future__ import annotations

import numpy as np

from ..body.body import Body
from ..errors import InvalidInput
from ..pattern.pattern import Pattern


def estimate_nodes(pattern: Pattern, spacing: float) -> int:
    """About how many nodes ``pattern`` meshes into at ``spacing`` [m]: a square grid inside
    each panel (area / spacing^2) and a row of nodes along its outline (perimeter / spacing)."""
    total = 0.0
    for panel in pattern.panels.values():
        polygon = panel.polygon()
        total += polygon.area / spacing**2 + polygon.length / spacing
    return int(np.ceil(total))


def check_placement(pattern: Pattern, body: Body, source: str = "") -> None:
    """Refuse a pattern whose placed panels cannot be sewn onto ``body``: a panel placed farther
    from the body's bounding box than the largest panel of the garment is across (a units slip
    in its translations, a panel sent away by mistake, a body given with the wrong up axis).
    Panels without a placement are put on the body by :func:`party.garment.dressing.dress`.
    ``source`` (the pattern file) begins the error."""
    vertices = body.vertices()
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    outlines = {name: panel.outline() for name, panel in pattern.panels.items()}
    size = max(float(np.max(points.max(axis=0) - points.min(axis=0))) for points in outlines.values())
    for name, panel in pattern.panels.items():
        if panel.placement is None:
            continue
        placed = panel.placement.apply(outlines[name])
        gap = np.linalg.norm(np.maximum(np.maximum(low - placed, placed - high), 0.0), axis=1)
        distance = float(gap.min())
        if distance > size:
            raise InvalidInput(f"{source + ': ' if source else ''}panel {name!r} is placed {distance:.3g} m from the body, farther than the garment's "
                               f"largest panel is across ({size:.2g} m): check its translation, the file's units and "
                               "the body's up axis (--up)")
