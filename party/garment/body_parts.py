"""Which body parts a garment's cloth passes through: GarmentCode's collision filter.

A panel labelled ``leg`` (a skirt's, a pair of trousers') passes through the arms
(:data:`~party.body.segmentation.ARMS`): in GarmentCode's A-pose the hands hang at the hips,
and a full skirt caught on them hangs from the fingertips, stretched, instead of from the
waist. A node sewn from several panels passes through a part only where all of them do, so
that a bodice sewn to a skirt still rests on the arms at its armholes.
"""

from __future__ import annotations

import numpy as np

from ..body.segmentation import ARMS
from .assemble import Garment

PASSES = {"leg": ARMS}
"""The body parts each panel label passes through."""


def garment_ignored_parts(garment: Garment) -> np.ndarray:
    """The body-part bits each garment node passes through, shape (n,) int32."""
    counts = np.diff(garment.node_offsets)
    return np.repeat([PASSES.get(mesh.panel.label, 0) for mesh in garment.panels], counts).astype(np.int32)


def sewn_ignored_parts(garment: Garment, node_map: np.ndarray) -> np.ndarray:
    """:func:`garment_ignored_parts` of the sewn nodes (``node_map``: garment node -> sewn
    node): the parts every garment node sewn into one passes through."""
    parts = np.full(int(node_map.max()) + 1, -1, np.int64)
    np.bitwise_and.at(parts, node_map, garment_ignored_parts(garment).astype(np.int64))
    return parts.astype(np.int32)
