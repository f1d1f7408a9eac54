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


def test_implicit_solver_refuses_hysteresis():
    net = rectangular_net(0.05, 0.05, 0.01)
    b = ModelBuilder()
    b.add_cloth(net, COTTON.with_(bending_hysteresis=1e-4), np.c_[net.uv, np.zeros(net.node_count)])
    with pytest.raises(InvalidInput, match="^bending hysteresis .* explicit solver only; use --solver explicit$"):
        SolverImplicit(b.finalize("cpu"))


def test_hysteresis_needs_bending_rigidity():
    with pytest.raises(InvalidInput, match="^fabric 'x': bending_hysteresis needs a bending_rigidity"):
        COTTON.with_(name="x", bending_rigidity=0.0, bending_hysteresis=1e-4)


@pytest.mark.parametrize("angle", [0.0, 30.0, 45.0, 90.0])
def test_frictional_moment_is_hb_whatever_the_direction_of_bending(angle):
    """Bending a sheet further along a cylinder by d(kappa) does work HB d(kappa) per unit
    area against the sliders, along the grain and along the bias alike: summed over the
    stencils that carry a slider, limit * |curvature| is HB * area * kappa."""
    from test_bending_shear import cylinder

    net = rectangular_net(0.4, 0.4, 0.005)
    b = ModelBuilder()
    two_hb = 2e-4
    b.add_cloth(net, COTTON.with_(bending_hysteresis=two_hb), np.c_[net.uv, np.zeros(net.node_count)])
    model = b.finalize("cpu")
    radius = 0.3
    points = cylinder(net, radius, angle)
    nodes, weights = model.hinge_nodes.numpy(), model.hinge_weights.numpy()
    curvature = np.linalg.norm(np.einsum("hk,hkc->hc", weights, points[nodes]), axis=1)
    sliding = model.hinge_friction.numpy() > 0
    work = np.sum(model.hinge_slip_limit.numpy()[sliding] * curvature[sliding])
    assert work == pytest.approx(0.5 * two_hb * 0.16 / radius, rel=0.03)
