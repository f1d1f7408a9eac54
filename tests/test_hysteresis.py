"""Bending hysteresis (Kawabata's 2HB): a Jenkins element beside each bending stencil."""

import numpy as np
import pytest

from party.errors import InvalidInput
from party.fabric import fabric_by_name
from party.model import ModelBuilder
from party.model.builder import HYSTERESIS_STIFFNESS
from party.meshing import rectangular_net
from party.solvers import SolverImplicit
from party.solvers.implicit.solver import MAX_SWEEPS, SLIDER_STEP_RATIO, STIFFNESS_PER_SWEEP, NodeCoupling
from party.units import GRAVITY
from party.validate import cantilever

COTTON = fabric_by_name("cotton")
OVERHANG = 0.6 * cantilever.reference_bending_length(COTTON)  # a small deflection
ROOT_MOMENT = COTTON.areal_density * GRAVITY * OVERHANG**2 / 2  # N*m/m


def tip_drop(two_hb: float, solver: str = "explicit", segments: int = 16) -> float:
    shape = cantilever.overhang_shape(COTTON.with_(bending_hysteresis=two_hb), solver, OVERHANG, segments)
    return -shape[-1, 1]


@pytest.mark.parametrize("solver,segments", [("explicit", 16), ("implicit", 4)])
@pytest.mark.slow
def test_moment_below_hb_everywhere_sticks_at_the_jenkins_stiffness(solver, segments):
    """With HB above the root moment W L^2 / 2 nothing slips: the strip bends as one of
    rigidity (1 + f) B, i.e. its tip drops 1 / (1 + f) as far (linear beam). The implicit
    solver's 1/300 s step is cut in three here (:data:`SLIDER_STEP_RATIO`); at f = 5 and as
    one step the strip fell 5 times as far."""
    free = tip_drop(0.0, solver, segments)
    stuck = tip_drop(2 * 4.0 * ROOT_MOMENT, solver, segments)
    assert stuck / free == pytest.approx(1.0 / (1.0 + HYSTERESIS_STIFFNESS), rel=0.02)


@pytest.mark.slow
def test_small_hysteresis_slips_and_bends_nearly_as_far():
    free = tip_drop(0.0)
    slipping = tip_drop(2 * 0.1 * ROOT_MOMENT)
    assert 0.9 * free < slipping < free


@pytest.mark.parametrize("spacing", [0.01, 0.003, 0.001])
def test_implicit_substeps_keep_the_sliders_bending_within_the_ratio(spacing):
    """The fewest substeps whose stuck bending stiffness over inertia at the sliders' nodes is at
    most SLIDER_STEP_RATIO; a fabric without hysteresis is cut only where its stiffness over
    inertia needs more than MAX_SWEEPS sweeps (at 1 mm: 2 substeps)."""
    net = rectangular_net(0.05, 0.05, spacing)
    dt = 1.0 / 300.0
    steps = {}
    for two_hb in (0.0, 1e-4):
        b = ModelBuilder()
        b.add_cloth(net, COTTON.with_(bending_hysteresis=two_hb), np.c_[net.uv, np.zeros(net.node_count)])
        model = b.finalize("cpu")
        steps[two_hb] = SolverImplicit(model, collision=None).substeps(dt)
    h = model.host
    stuck = model.bending_matrix(friction=True).diagonal()
    sliders = np.unique(h.hinge_nodes[h.hinge_friction > 0.0])
    ratio = float(np.max(stuck[sliders] / h.mass[sliders])) * dt**2
    count = steps[1e-4]
    bend = model.bending_matrix(friction=False)
    stiffness = NodeCoupling.of(model, bend).largest_rate() * dt**2 / (STIFFNESS_PER_SWEEP * MAX_SWEEPS)
    cut = steps[0.0]
    assert cut == (1 if spacing > 0.001 else 2)
    assert stiffness <= cut**2 and (cut == 1 or stiffness > (cut - 1) ** 2)
    assert ratio / count**2 <= SLIDER_STEP_RATIO
    assert count == cut or ratio / (count - 1) ** 2 > SLIDER_STEP_RATIO


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
