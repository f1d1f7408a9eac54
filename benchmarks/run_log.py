"""Runs of ``compare.py`` kept as each finishes, so that a stopped comparison can go on (``--resume``).

``OUT/runs.jsonl`` holds a line per finished run: its scene, system, round, the settings it ran
with and its row of results; ``OUT/runs/*.npz`` the final points [m] and triangles of the runs
that have them, which the report compares shapes with. A resumed comparison takes every run
the log holds for the same scene, system, round and settings, made by the same code (the
settings carry a digest of the sources the system's runs depend on, :func:`source_digest`), and
runs the rest; without ``--resume`` the log starts empty.
"""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np

ARRAYS = ("points", "triangles")


def source_digest(paths: list[Path], extra: str = "") -> str:
    """A digest of the files under ``paths`` (names and contents, compiled caches left out) and
    of ``extra``: what a kept run was made with, so that one made before the code changed is run
    again rather than reported as this code's."""
    digest = hashlib.sha1(extra.encode())
    for root in paths:
        files = [root] if root.is_file() else sorted(p for p in root.rglob("*") if p.is_file())
        for path in files:
            if "__pycache__" in path.parts or path.suffix == ".pyc":
                continue
            digest.update(path.as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


class RunLog:
    """The log of runs under ``out`` (see the module docstring); ``resume`` keeps what it holds."""

    def __init__(self, out: Path, resume: bool) -> None:
        self.path = Path(out) / "runs.jsonl"
        self.arrays = Path(out) / "runs"
        self._done: dict[str, dict] = {}
        if resume and self.path.exists():
            for line in self.path.read_text().splitlines():
                entry = json.loads(line)
                self._done[entry["key"]] = entry
        else:
            self.path.unlink(missing_ok=True)
            shutil.rmtree(self.arrays, ignore_errors=True)

    @staticmethod
    def _key(scene: str, system: str, round_: int, settings: dict) -> str:
        return json.dumps([scene, system, round_, settings], sort_keys=True)

    def get(self, scene: str, system: str, round_: int, settings: dict) -> dict | None:
        """The row of that run, arrays included, or None where the log does not hold it."""
        entry = self._done.get(self._key(scene, system, round_, settings))
        if entry is None:
            return None
        row = dict(entry["row"])
        if entry.get("arrays"):
            with np.load(self.arrays / entry["arrays"]) as saved:
                row.update({name: saved[name] for name in ARRAYS})
        return row

    def put(self, scene: str, system: str, round_: int, settings: dict, row: dict) -> None:
        """Keep the finished run's ``row``: its arrays in their own file, the rest as a line of the log."""
        key = self._key(scene, system, round_, settings)
        entry = {"key": key, "row": {k: v for k, v in row.items() if k not in ARRAYS}, "arrays": None}
        if all(name in row for name in ARRAYS):
            entry["arrays"] = hashlib.sha1(key.encode()).hexdigest()[:16] + ".npz"
            self.arrays.mkdir(parents=True, exist_ok=True)
            np.savez(self.arrays / entry["arrays"], **{name: np.asarray(row[name]) for name in ARRAYS})
        with open(self.path, "a") as log:
            log.write(json.dumps(entry) + "\n")
        self._done[key] = entry
