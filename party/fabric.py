"""Fabrics: the material parameters of the cloth, in SI units.

The library ``party/data/fabrics.toml`` holds the paper's wool flannel (Table 1) and measured
or estimated everyday fabrics, each with its sources; users give their own in the same keys
as a TOML or JSON file (:func:`load_fabric`). Unit conversions (Table 1's printed units,
Kawabata's KES units) live in :mod:`party.units`.
"""

from __future__ import annotations

import math
from functools import lru_cache
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path

from . import units
from .errors import InvalidInput


@dataclass(frozen=True)
class Fabric:
    """Material of a cloth, SI units throughout.

    Attributes:
        name: A label.
        areal_density: Mass per unit area rho [kg/m^2] (eq. 3).
        tensile_warp: Stretch stiffness along the warp (grain) [N/m]: force per unit width per
            unit strain; element spring constant is ``tensile_warp * width / rest_length``.
        tensile_weft: Stretch stiffness along the weft [N/m].
        damping: rho_visco [kg/(m^2 s)]: viscous force on a node is
            ``damping * area * sum_k (v_k - v_i)`` (section 5).
        strain_limit: L_sh, the plastic limit [-]: no element elongates beyond
            ``(1 + strain_limit) * rest_length``. ``math.inf`` disables it.
        restitution: sigma, the cloth's "elasticity coefficient" against a body (eq. 11).
        friction: mu, cloth-body friction coefficient (eq. 10).
        momentum_propagation: gamma of the cloth-cloth exchange (eqs. 13-14), in [0, 1].
        cloth_friction: kappa, the loss to cloth-cloth friction (eqs. 13-14), in [0, 1].
        thickness: eps, the collision thickness [m] kept between cloth and body and between
            layers (section 6.1).
        shear: In-plane shear stiffness G [N/m per radian of shear angle], carried by the
            net's diagonal elements (0: none, as in the paper).
        bending_rigidity: Bending rigidity B [N*m]: moment per unit width per unit curvature,
            carried by curvature stencils along the threads and twist stencils on the grid's
            quads (:mod:`party.meshing.hinges`; 0: none, as in the paper).
        bending_hysteresis: Kawabata's bending hysteresis 2HB [N*m/m]: the width of the
            moment-curvature loop. Bending then meets a frictional moment of up to HB = 2HB / 2
            per unit width, which holds the cloth in any shape where it is not exceeded (a
            Jenkins element, ``HYSTERESIS_STIFFNESS`` times as stiff as the bending
            (:mod:`party.model.builder`), beside each thread's bending stencil);
            0: none.
        membrane: Carry the in-plane elasticity on the triangles as a continuum membrane
            (orthotropic St. Venant-Kirchhoff in plane stress: Young's moduli times thickness
            ``tensile_warp`` and ``tensile_weft`` [N/m], shear modulus times thickness
            ``shear`` [N/m], Poisson's ratio ``poisson``; the paper's section 8) instead of
            the net's springs. The warp and weft elements then keep only their dampers and
            the plastic limit. Implicit solver only.
        poisson: Poisson's ratio nu_12 of the membrane: the weft contraction per unit warp
            stretch [-]; nu_21 = nu_12 tensile_weft / tensile_warp.
        description, source: Free text; a library fabric names where its values come from.

    The defaults of ``strain_limit``, ``restitution``, ``friction``, ``momentum_propagation``
    and ``cloth_friction`` are Table 1's, so a fabric that gives none has the paper's contact
    and plastic limit; ``thickness`` defaults to 3 mm, about a wool flannel's.
    """

    name: str
    areal_density: float
    tensile_warp: float
    tensile_weft: float
    damping: float
    strain_limit: float = 0.0995
    restitution: float = 0.03
    friction: float = 0.6
    momentum_propagation: float = 0.5
    cloth_friction: float = 0.23
    thickness: float = 3.0e-3
    shear: float = 0.0
    bending_rigidity: float = 0.0
    bending_hysteresis: float = 0.0
    membrane: bool = False
    poisson: float = 0.0
    description: str = ""
    source: str = ""

    def __post_init__(self) -> None:
        positive = ("areal_density", "tensile_warp", "tensile_weft", "thickness")
        for field in positive:
            value = getattr(self, field)
            if not (math.isfinite(value) and value > 0.0):
                raise InvalidInput(f"fabric {self.name!r}: {field} must be positive and finite, got {value}")
        for field in ("damping", "shear", "bending_rigidity", "bending_hysteresis"):
            value = getattr(self, field)
            if not (math.isfinite(value) and value >= 0.0):
                raise InvalidInput(f"fabric {self.name!r}: {field} must be non-negative and finite, got {value}")
        if not (0.0 <= self.poisson and self.poisson**2 * self.tensile_weft / self.tensile_warp < 1.0):
            raise InvalidInput(f"fabric {self.name!r}: poisson must be non-negative with "
                               f"poisson^2 tensile_weft / tensile_warp below 1, got {self.poisson}")
        if self.bending_hysteresis > 0.0 and self.bending_rigidity == 0.0:
            raise InvalidInput(f"fabric {self.name!r}: bending_hysteresis needs a bending_rigidity (its friction acts "
                               "beside the bending stencils)")
        if not self.strain_limit > 0.0:
            raise InvalidInput(f"fabric {self.name!r}: strain_limit must be positive, got {self.strain_limit}")
        for field in ("restitution", "momentum_propagation", "cloth_friction"):
            value = getattr(self, field)
            if not 0.0 <= value <= 1.0:
                raise InvalidInput(f"fabric {self.name!r}: {field} must lie in [0, 1], got {value}")
        if not (math.isfinite(self.friction) and self.friction >= 0.0):
            raise InvalidInput(f"fabric {self.name!r}: friction must be non-negative, got {self.friction}")

    def with_(self, **changes: float) -> "Fabric":
        """A copy with some parameters changed (validated again)."""
        return replace(self, **changes)

    def to_dict(self) -> dict:
        return asdict(self)


def wool_flannel() -> Fabric:
    """The paper's wool flannel (Table 1), from the library (its conversion is tested against
    :mod:`party.units`)."""
    return library()["wool_flannel"]


LIBRARY = Path(__file__).parent / "data" / "fabrics.toml"
"""The fabric library shipped with party."""

_NUMBERS = {f.name for f in fields(Fabric) if f.type in ("float", float)}
_TEXT = {"description", "source"}
_FLAGS = {"membrane"}
_KES = {
    "areal_density_kes": ("areal_density", units.areal_density_from_mg_per_cm2),
    "tensile_warp_kes": ("tensile_warp", units.tensile_stiffness_from_kes),
    "tensile_weft_kes": ("tensile_weft", units.tensile_stiffness_from_kes),
    "shear_kes": ("shear", units.shear_stiffness_from_kes),
    "bending_rigidity_kes": ("bending_rigidity", units.bending_rigidity_from_kes),
    "bending_hysteresis_kes": ("bending_hysteresis", units.bending_hysteresis_from_kes),
}


PHYSICAL_RANGES: dict[str, tuple[float, float, str]] = {
    "areal_density": (0.005, 3.0, "kg/m^2"),
    "tensile_warp": (1.0, 1.0e6, "N/m"),
    "tensile_weft": (1.0, 1.0e6, "N/m"),
    "damping": (0.0, 1.0e4, "kg/(m^2 s)"),
    "thickness": (1.0e-4, 0.05, "m"),
    "shear": (0.0, 1.0e5, "N/m"),
    "bending_rigidity": (0.0, 1.0e-2, "N*m"),
    "bending_hysteresis": (0.0, 1.0, "N*m/m"),
    "strain_limit": (1.0e-3, math.inf, ""),
    "friction": (0.0, 5.0, ""),
}
"""Ranges a fabric file's values must lie in (SI): wide enough for every real cloth, from tulle
(some 10 g/m^2) to heavy leather and coated technical fabrics (tensile stiffness up to some
1e5 N/m), so that a value outside is a slip of units or digits. Fabrics built in code
(:meth:`Fabric.with_`) are not held to them."""


def fabric_from_mapping(name: str, values: dict, *, origin: str = "fabric") -> Fabric:
    """A :class:`Fabric` from a table of the library's keys (SI, or KES where the key ends in
    ``_kes``); ``origin`` names the file in error messages."""
    if not isinstance(values, dict):
        raise InvalidInput(f"{origin}: fabric {name!r} must be a table of values")
    given: dict = {}
    for key, value in values.items():
        if key in _TEXT:
            given[key] = str(value)
            continue
        if key in _FLAGS:
            if not isinstance(value, bool):
                raise InvalidInput(f"{origin}: fabric {name!r}: {key} must be true or false, got {value!r}")
            given[key] = value
            continue
        if key not in _NUMBERS and key not in _KES:
            known = ", ".join(sorted(_NUMBERS | set(_KES) | _TEXT | _FLAGS - {"name"}))
            raise InvalidInput(f"{origin}: fabric {name!r} has unknown key {key!r} (known: {known})")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InvalidInput(f"{origin}: fabric {name!r}: {key} must be a number, got {value!r}")
        field, convert = _KES.get(key, (key, float))
        if field in given:
            raise InvalidInput(f"{origin}: fabric {name!r} gives {field} twice (SI and KES)")
        given[field] = convert(float(value))
        low, high, unit = PHYSICAL_RANGES.get(field, (-math.inf, math.inf, ""))
        if not low <= given[field] <= high:
            stated = "" if field == key else f" (from {key} = {value:g})"
            raise InvalidInput(f"{origin}: fabric {name!r}: {field} = {given[field]:g} {unit}{stated} is outside "
                               f"{low:g}-{high:g} {unit}, the range of real cloth")
    missing = [k for k in ("areal_density", "tensile_warp", "tensile_weft", "damping") if k not in given]
    if missing:
        raise InvalidInput(f"{origin}: fabric {name!r} lacks {', '.join(missing)}")
    given.pop("name", None)
    return Fabric(name=name, **given)


def library() -> dict[str, Fabric]:
    """All fabrics of the library, by name."""
    return dict(_library())


@lru_cache(maxsize=1)
def _library() -> dict[str, Fabric]:
    return {name: fabric_from_mapping(name, table, origin=LIBRARY.name)
            for name, table in _read_document(LIBRARY).items()}


def load_fabric(path: str | Path) -> Fabric:
    """A fabric from a TOML or JSON file holding one fabric's keys at its top level (its name is
    the ``name`` key or the file's stem)."""
    path = Path(path)
    document = _read_document(path)
    return fabric_from_mapping(str(document.get("name", path.stem)), document, origin=path.name)


def fabric_by_name(spec: str) -> Fabric:
    """A library fabric by name, or a fabric file (``.toml`` or ``.json``) by path."""
    if spec.endswith((".toml", ".json")) or Path(spec).is_file():
        return load_fabric(spec)
    fabrics = library()
    if spec not in fabrics:
        raise InvalidInput(f"unknown fabric {spec!r}; known: {', '.join(sorted(fabrics))}, or a .toml/.json file")
    return fabrics[spec]


def _read_document(path: Path) -> dict:
    import json
    import tomllib

    if not path.is_file():
        raise InvalidInput(f"fabric file not found: {path}")
    try:
        if path.suffix == ".json":
            document = json.loads(path.read_text())
        elif path.suffix == ".toml":
            document = tomllib.loads(path.read_text())
        else:
            raise InvalidInput(f"fabric file {path.name}: expected a .toml or .json file")
    except (json.JSONDecodeError, tomllib.TOMLDecodeError) as exc:
        raise InvalidInput(f"fabric file {path.name} is not valid {path.suffix[1:].upper()}: {exc}") from None
    if not isinstance(document, dict):
        raise InvalidInput(f"fabric file {path.name}: expected a table of values")
    return document
