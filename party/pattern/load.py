"""Reading a pattern file of any supported format: ours (JSON), GarmentCode's (JSON) or
DXF-AAMA; checks that its sizes are plausible for a garment in the units it declares."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import InvalidInput
from .garmentcode import is_garmentcode, pattern_from_garmentcode
from .party_json import pattern_from_document
from .pattern import Pattern

PANEL_SIZE_RANGE = (0.01, 4.0)
"""Smallest and largest plausible panel extent [m]; outside it the units are wrong."""


def load_pattern(path, *, seams_file=None, units: str | None = None) -> Pattern:
    """Load ``path`` (.json: ours or GarmentCode's, told apart by content; .dxf: AAMA).

    Raises :class:`InvalidInput` with a one-line message naming the file and the panel, edge
    or seam at fault."""
    path = Path(path)
    if not path.exists():
        raise InvalidInput(f"{path}: pattern file not found")
    suffix = path.suffix.lower()
    if suffix == ".dxf":
        from .dxf_aama import load_dxf_pattern

        pattern = load_dxf_pattern(path, seams_file=seams_file, units=units)
    elif suffix == ".json":
        try:
            doc = json.loads(path.read_text())
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise InvalidInput(f"{path}: not valid JSON ({getattr(exc, 'msg', exc)})") from None
        if isinstance(doc, dict) and doc.get("format") == "party-pattern":
            pattern = pattern_from_document(doc, str(path))
        elif is_garmentcode(doc):
            pattern = pattern_from_garmentcode(doc, str(path))
        else:
            raise InvalidInput(f"{path}: not a pattern (expected our format with \"format\": \"party-pattern\" "
                               "or a GarmentCode specification with pattern.panels)")
    else:
        raise InvalidInput(f"{path}: unknown pattern format {suffix or '(no suffix)'} (expected .json or .dxf)")
    check_sizes(pattern, str(path))
    return pattern


def check_sizes(pattern: Pattern, source: str) -> None:
    """Raise if a panel is too small or too large to be a garment piece in metres."""
    lo, hi = PANEL_SIZE_RANGE
    for panel in pattern.panels.values():
        pts = panel.outline()
        extent = float(np.max(pts.max(axis=0) - pts.min(axis=0)))
        if not lo <= extent <= hi:
            raise InvalidInput(f"{source}: panel {panel.name!r} is {extent:.4g} m across, outside "
                               f"{lo}-{hi} m: the file's units do not match its numbers")
