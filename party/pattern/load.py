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
    ``seams_file`` and ``units`` apply to DXF patterns only (a JSON pattern names its own).

    Raises :class:`InvalidInput` with a one-line message naming the file and the panel, edge
    or seam at fault."""
    path = Path(path)
    if not path.exists():
        raise InvalidInput(f"{path}: pattern file not found")
    if path.is_dir():
        raise InvalidInput(f"{path} is a folder, not a pattern file (expected a .json or .dxf file)")
    suffix = path.suffix.lower()
    if suffix not in (".dxf", ".json"):
        raise InvalidInput(f"{path}: unknown pattern format {suffix or '(no suffix)'} (expected .json or .dxf)")
    if suffix == ".json":
        for flag, value in (("--units", units), ("--seams", seams_file)):
            if value is not None:
                raise InvalidInput(f"{flag} applies to DXF patterns only; {path} is a JSON pattern, which gives its "
                                   "own units and seams")
    try:
        if suffix == ".dxf":
            from .dxf_aama import load_dxf_pattern

            pattern = load_dxf_pattern(path, seams_file=seams_file, units=units)
        else:
            pattern = _load_json(path)
        check_sizes(pattern, str(path))
    except InvalidInput as error:
        message = str(error)
        if message.startswith(str(path)) or (seams_file is not None and message.startswith(str(seams_file))):
            raise
        raise InvalidInput(f"{path}: {message}") from None
    return pattern


def _load_json(path: Path) -> Pattern:
    try:
        text = path.read_bytes().decode("utf-8-sig")  # a byte-order mark, as some editors write, is fine
    except UnicodeDecodeError:
        raise InvalidInput(f"{path}: not a UTF-8 text file (save it as UTF-8)") from None
    except OSError as error:
        raise InvalidInput(f"{path}: cannot read the file ({error.strerror})") from None
    if not text.strip():
        raise InvalidInput(f"{path}: the file is empty")
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InvalidInput(f"{path}: not valid JSON ({exc.msg} at line {exc.lineno}, column {exc.colno})") from None
    if isinstance(doc, dict) and doc.get("format") == "party-pattern":
        return pattern_from_document(doc, str(path))
    if is_garmentcode(doc):
        return pattern_from_garmentcode(doc, str(path))
    raise InvalidInput(f"{path}: not a pattern (expected our format with \"format\": \"party-pattern\" "
                       "or a GarmentCode specification with pattern.panels)")


def check_sizes(pattern: Pattern, source: str) -> None:
    """Raise if a panel is too small or too large to be a garment piece in metres."""
    lo, hi = PANEL_SIZE_RANGE
    for panel in pattern.panels.values():
        pts = panel.outline()
        extent = float(np.max(pts.max(axis=0) - pts.min(axis=0)))
        if not lo <= extent <= hi:
            raise InvalidInput(f"{source}: panel {panel.name!r} is {extent:.4g} m across, outside "
                               f"{lo}-{hi} m: the file's units do not match its numbers")
