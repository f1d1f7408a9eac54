"""Fabrics: the material parameters of the paper's elastic net, in SI units.

The faithful preset :func:`wool_flannel` reproduces Table 1 of the paper; the conversions of
its printed units live in :mod:`party.units`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

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
        shear: Stiffness of the optional diagonal shear elements [N/m] (0: none, as in the paper).
        bending: Stiffness of the optional skip-one bending elements [N/m] (0: none, as in the
            paper).
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
    bending: float = 0.0

    def __post_init__(self) -> None:
        positive = ("areal_density", "tensile_warp", "tensile_weft", "thickness")
        for field in positive:
            value = getattr(self, field)
            if not (math.isfinite(value) and value > 0.0):
                raise InvalidInput(f"fabric {self.name!r}: {field} must be positive and finite, got {value}")
        for field in ("damping", "shear", "bending"):
            value = getattr(self, field)
            if not (math.isfinite(value) and value >= 0.0):
                raise InvalidInput(f"fabric {self.name!r}: {field} must be non-negative and finite, got {value}")
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
    """The paper's wool flannel, Table 1, converted to SI by :mod:`party.units`."""
    return Fabric(
        name="wool_flannel",
        areal_density=units.areal_density_from_g_per_cm2(0.023),
        tensile_warp=units.tensile_stiffness_from_table1(1000.0),
        tensile_weft=units.tensile_stiffness_from_table1(920.0),
        damping=units.damping_from_table1(4.0),
        strain_limit=0.0995,
        restitution=0.03,
        friction=0.6,
        momentum_propagation=0.5,
        cloth_friction=0.23,
    )


PRESETS = {"wool_flannel": wool_flannel}


def fabric_by_name(name: str) -> Fabric:
    """Look a preset up by name; a clear error lists the known ones."""
    try:
        return PRESETS[name]()
    except KeyError:
        raise InvalidInput(f"unknown fabric {name!r}; known: {', '.join(sorted(PRESETS))}") from None
