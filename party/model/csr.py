"""Compressed rows: lists of entries per node, stored node by node."""

from __future__ import annotations

import numpy as np


def csr_order(rows: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """For entries belonging to ``rows`` (ids below ``count``): the offsets (count + 1, int64)
    of each row's entries once sorted by row, and the stable order that sorts them."""
    rows = np.asarray(rows, np.int64)
    offsets = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=count))]).astype(np.int64)
    return offsets, np.argsort(rows, kind="stable")
