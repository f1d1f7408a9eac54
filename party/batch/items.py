"""What a batch drapes: every pattern on every body in every fabric, one item each.

Patterns are named by files, folders (every pattern file inside, not recursing) or globs; an
item's name, ``<pattern>__<body>__<fabric>``, is also its folder in the dataset, so names must
be unique within a batch (two patterns of one name in different folders are refused).
"""

from __future__ import annotations

import glob
from dataclasses import dataclass
from pathlib import Path

from ..errors import InvalidInput

PATTERN_SUFFIXES = (".json", ".dxf")
"""File suffixes ``party drape`` reads as patterns (a folder's or glob's other files are left out)."""

SPEC_SUFFIX = "_specification"
"""GarmentCode's pattern file name ends so; an item is named without it."""


@dataclass(frozen=True)
class BatchItem:
    """One drape of a batch: ``pattern`` (a file), ``body`` (a dress-form size or a mesh file)
    and ``fabric`` (a library name or a file), as ``party drape`` takes them."""

    pattern: Path
    body: str
    fabric: str

    @property
    def name(self) -> str:
        """``<pattern>__<body>__<fabric>``: the item's folder in the dataset."""
        pattern = self.pattern.stem.removesuffix(SPEC_SUFFIX)
        return f"{pattern}__{Path(self.body).stem}__{Path(self.fabric).stem}"

    def columns(self) -> dict:
        """The item's own manifest columns: its name and inputs."""
        return {"item": self.name, "pattern": str(self.pattern), "body": self.body, "fabric": self.fabric}


def pattern_files(given: list[str]) -> list[Path]:
    """The pattern files ``given`` names, in order, each once: files as they are, folders' pattern
    files sorted by name, globs' matches sorted. A name that matches nothing is refused."""
    found: list[Path] = []
    for text in given:
        path = Path(text)
        if path.is_dir():
            matches = sorted(p for p in path.iterdir() if _is_pattern(p))
            if not matches:
                raise InvalidInput(f"{text}: the folder holds no pattern files ({', '.join(PATTERN_SUFFIXES)})")
        elif path.is_file():
            matches = [path]
        elif glob.has_magic(text):
            matches = sorted(Path(p) for p in glob.glob(text) if _is_pattern(Path(p)))
            if not matches:
                raise InvalidInput(f"{text}: no pattern file matches")
        else:
            raise InvalidInput(f"{text}: no such pattern file or folder")
        found.extend(p for p in matches if p not in found)
    return found


def _is_pattern(path: Path) -> bool:
    """A pattern file by its name: a DXF seams side file (``*.seams.json``) is not one."""
    return path.is_file() and path.suffix.lower() in PATTERN_SUFFIXES and not path.name.endswith(".seams.json")


def plan(patterns: list[str], bodies: list[str], fabrics: list[str]) -> list[BatchItem]:
    """Every pattern on every body in every fabric, patterns outermost."""
    if not bodies or any(not b.strip() for b in bodies):
        raise InvalidInput("--bodies names no body; give dress-form sizes or mesh files, comma-separated")
    if not fabrics or any(not f.strip() for f in fabrics):
        raise InvalidInput("--fabrics names no fabric; give library names or files, comma-separated")
    items = [BatchItem(p, b, f) for p in pattern_files(patterns) for b in bodies for f in fabrics]
    seen: dict[str, BatchItem] = {}
    for item in items:
        if item.name in seen:
            raise InvalidInput(f"two items of the batch would share the folder {item.name!r} ({seen[item.name].pattern} "
                               f"and {item.pattern}); rename one of them")
        seen[item.name] = item
    return items
