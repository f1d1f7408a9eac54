"""A body's measurements as GarmentCode gives them: a YAML file beside the mesh, ``NAME.yaml``,
holding ``body:`` lengths in centimetres whatever the mesh's units (``height``, ``head_l``,
``waist_line``, ``armscye_depth``, ``neck_w``, ...) and a few angles in degrees. Read once when
the body loads, lengths turned into metres: the sizes GarmentCode fitted its designs to
(``Body.measurements``), for what needs a body's proportions rather than its mesh."""

from __future__ import annotations

from pathlib import Path

from ..errors import InvalidInput

ANGLES = frozenset({"arm_pose_angle", "shoulder_incl", "hip_inclination"})
"""The entries in degrees; every other number is a length."""

CENTIMETRE = 0.01
"""Metres per unit of GarmentCode's measurements."""


def read_measurements(mesh: Path) -> dict[str, float]:
    """The measurements in ``mesh``'s sibling ``.yaml`` (lengths [m], angles [deg]); empty where
    there is none. A file that is there but unreadable is an error, not a body without
    measurements: whoever put it there meant it to be used."""
    path = mesh.with_suffix(".yaml")
    if not path.is_file():
        return {}
    import yaml

    try:
        doc = yaml.safe_load(path.read_text())
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        raise InvalidInput(f"{path}: not readable YAML ({type(exc).__name__}); fix or remove the body's measurements "
                           "file") from None
    body = doc.get("body") if isinstance(doc, dict) else None
    if not isinstance(body, dict):
        raise InvalidInput(f"{path}: expected GarmentCode's body measurements under 'body:'")
    numbers = {str(k): float(v) for k, v in body.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
    return {k: (v if k in ANGLES else v * CENTIMETRE) for k, v in numbers.items()}
