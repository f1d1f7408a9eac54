"""Bending hysteresis (Kawabata's 2HB): a Jenkins element beside each bending stencil."""

import numpy as np
import pytest

from party.errors import InvalidInput
from party.fabric import fabric_by_name
from party.model import ModelBuilder
from party.model.builder import HYSTERESIS_STIFFNESS
from party.meshing import rectangular_net
from party.solvers import SolverImplicit
from party.units import GRAVITY
from party.validate import cantilever

COTTON = fabric_by_name("cotton")
OVERHANG = 0.6 * cantilever.reference_bending_length(COTTON)  # a small deflection
ROOT_MOMENT = COTTON.areal_density * GRAVITY * OVERHANG**2 / 2  # N*m/m


def tip_drop(two_hb: float) -> float:
    shape = cantilever.overhang_shape(COTTON.with_(bending_hysteresis=two_hb), "explicit", OVERHANG, 16)
    return -shape[-1, 1]


def test_moment_below_hb_everywhere_sticks_at_the_jenkins_stiffness():
    """With HB above the root moment W L^2 / 2 nothing slips: the strip bends as one of
    rigidity (1 + f) B, i.e. its tip drops 1 / (1 + f) as far (linear beam)."""
    free = tip_drop(0.0)
    stuck = tip_drop(2 * 4.0 * ROOT_MOMENT)
    assert stuck / free == pytest.approx(1.0 / (1.0 + HYSTERESIS_STIFFNESS), rel=0.02)


def test_small_hysteresis_slips_and_bends_nearly_as_far():
    free = tip_drop(0.0)
    slipping = tip_drop(2 * 0.1 * ROOT_MOMENT)
    assert 0.9 * free < slipping < free


def test_hysteresis_needs_bending_rigidity():
    with pytest.raises(InvalidInput, match="^fabric 'x': bending_hysteresis needs a bending_rigidity"):
        COTTON.with_(name="x", bending_rigidity=0.0, bending_hysteresis=1e-4)


def test_implicit_solver_refuses_hysteresis():
    net = rectangular_net(0.05, 0.05, 0.01)
    b = ModelBuilder()
    b.add_cloth(net, COTTON.with_(bending_hysteresis=1e-4), np.c_[net.uv, np.zeros(net.node_count)])
    with pytest.raises(InvalidInput, match="^bending hysteresis .* explicit solver only; use --solver explicit$"):
        SolverImplicit(b.finalize("cpu"))
