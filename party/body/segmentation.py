"""Body parts of a body's vertices, for collision filters: GarmentCode's segmentation.

GarmentCode ships ``ggg_body_segmentation.json`` beside its bodies: for each part (``body``,
``left_arm``, ``right_arm``, ``left_leg``, ``right_leg``, ``face_internal``) the indices of
the vertices in it, the same for every body of its model (one topology). Its simulator lets a
skirt's or a pair of trousers' cloth through the arms: in an A-pose the hands hang at the hips,
and a full skirt draped over them hangs from the fingertips instead of from the waist.

A body carries the parts as one bit per part per vertex (0: in none);
a face belongs to a part when all three of its corners do, so that
the faces where an arm joins the shoulder still collide with everything.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import InvalidInput

PARTS = ("body", "left_arm", "right_arm", "left_leg", "right_leg", "face_internal")
"""GarmentCode's body parts, in the order of their bits."""

SHARED_FILE = "ggg_body_segmentation.json"
"""The segmentation GarmentCode keeps beside all its bodies."""


def part_bits(*names: str) -> int:
    """The bit mask of the named parts (of :data:`PARTS`)."""
    return sum(1 << PARTS.index(name) for name in names)


ARMS = part_bits("left_arm", "right_arm")
"""The parts a garment's ``leg`` panels (skirts, trousers) pass through."""


def read_segmentation(mesh: Path, vertex_count: int) -> np.ndarray | None:
    """The part bits of each of the ``vertex_count`` vertices of the body mesh ``mesh``, shape
    (n,) int32, from ``NAME_segmentation.json`` beside it or else the folder's
    :data:`SHARED_FILE`; None where there is neither. The folder's shared file serves only a
    mesh of its topology (every index it lists is a vertex, and it labels all but a hundredth
    of them): another body in the folder is not segmented by it. A body's own file that does
    not fit it is an error."""
    own = mesh.with_name(f"{mesh.stem}_segmentation.json")
    path = own if own.is_file() else mesh.with_name(SHARED_FILE)
    if not path.is_file():
        return None
    try:
        doc = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InvalidInput(f"{path}: not valid JSON ({type(exc).__name__}); fix or remove the body's "
                           "segmentation file") from None
    if not isinstance(doc, dict) or not all(isinstance(v, list) for v in doc.values()):
        raise InvalidInput(f"{path}: expected body parts, each a list of vertex indices")
    bits = np.zeros(vertex_count, np.int32)
    labelled = np.zeros(vertex_count, bool)
    fits = True
    for name, indices in doc.items():
        if name not in PARTS:
            continue
        ids = np.asarray(indices)
        if ids.size and (not np.issubdtype(ids.dtype, np.integer) or ids.min() < 0 or ids.max() >= vertex_count):
            fits = False
            break
        bits[ids] |= part_bits(name)
        labelled[ids] = True
    fits = fits and labelled.mean() >= 0.99
    if fits:
        return bits
    if path == own:
        raise InvalidInput(f"{path}: its vertex indices do not fit {mesh.name} ({vertex_count} vertices)")
    return None
