"""A batch's manifest: ``DATASET/manifest.parquet``, one row per item done, rewritten whole
(atomically) as each item finishes, so that a batch killed at any moment keeps every row it had.

Rows are kept in the batch's item order, whatever order the items finished in, so that a
batch resumed after a kill writes the manifest an uninterrupted batch writes (but for the
wall times).
"""

from __future__ import annotations

import os
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from ..errors import InvalidInput

STATUSES = ("passed", "failed", "error", "timeout")
"""An item's status: every quality gate passed; a gate missed; the drape could not run or died
(bad input, a blow-up, a crash, killed); it ran past its time limit."""

SCHEMA = pa.schema([
    ("item", pa.string()), ("pattern", pa.string()), ("body", pa.string()), ("fabric", pa.string()),
    ("status", pa.string()), ("reasons", pa.list_(pa.string())),
    ("nodes", pa.int64()), ("wall_seconds", pa.float64()),
    ("max_seam_gap_mm", pa.float64()), ("max_elongation", pa.float64()), ("body_penetrations", pa.int64()),
    ("cloth_crossings", pa.int64()), ("at_rest", pa.bool_()), ("draping_steps", pa.int64()),
    ("nearest_body_mm", pa.float64()), ("median_body_mm", pa.float64()),
])
"""The manifest's columns: the item and its inputs, its status and gate reasons (for an error,
the error's one line), nodes, wall seconds, and the summary's metrics (null for an error)."""


class Manifest:
    """The manifest at ``path`` of a batch of ``order`` (item names, in the batch's order)."""

    def __init__(self, path: Path, order: list[str]) -> None:
        self.path = Path(path)
        self.order = {name: k for k, name in enumerate(order)}
        self.rows: dict[str, dict] = {}

    def load(self) -> None:
        """Take the rows of an existing manifest (a resumed batch) for items of this batch."""
        if not self.path.exists():
            return
        try:
            table = pq.read_table(self.path)
        except (OSError, pa.ArrowException) as error:
            raise InvalidInput(f"{self.path} is not a readable manifest ({error}); remove it or drop --resume") from None
        missing = set(SCHEMA.names) - set(table.column_names)
        if missing:
            raise InvalidInput(f"{self.path} is not a party batch manifest (no {', '.join(sorted(missing))} column)")
        for row in table.select(SCHEMA.names).to_pylist():
            if row["item"] in self.order:
                self.rows[row["item"]] = row

    def __contains__(self, name: str) -> bool:
        return name in self.rows

    def add(self, row: dict) -> None:
        """Record ``row`` (the columns of :data:`SCHEMA`) and rewrite the manifest."""
        if row["status"] not in STATUSES:
            raise ValueError(f"unknown status {row['status']!r}")
        self.rows[row["item"]] = {name: row.get(name) for name in SCHEMA.names}
        self.write()

    def write(self) -> None:
        rows = sorted(self.rows.values(), key=lambda r: self.order.get(r["item"], len(self.order)))
        table = pa.Table.from_pylist(rows, schema=SCHEMA)
        part = self.path.with_name(self.path.name + ".part")
        pq.write_table(table, part)
        os.replace(part, self.path)
