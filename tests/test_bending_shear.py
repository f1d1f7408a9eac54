"""Bending stencils and shear diagonals against plate and membrane theory."""

import numpy as np
import pytest
import warp as wp

from party.fabric import library
from party.meshing import rectangular_net
from party.meshing.hinges import bending_energy, hinges
from party.model import ModelBuilder
from party.solvers.explicit.kernels import hinge_forces
from party.solvers.relax import total_energy

B = 1.0e-5  # N*m


def cylinder(net, radius, angle_deg):
    """The flat net wrapped on a cylinder of ``radius`` whose curvature runs at ``angle_deg``
    to the warp: arc length preserved."""
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    u = net.uv[:, 0] * c + net.uv[:, 1] * s
    v = -net.uv[:, 0] * s + net.uv[:, 1] * c
    return np.c_[radius * np.sin(u / radius), v, radius * (1.0 - np.cos(u / radius))]


@pytest.mark.parametrize("angle", [0.0, 45.0, 90.0])
def test_bending_in_any_direction_stores_the_plate_energy(angle):
    """A plate of rigidity B bent to radius R stores B / (2 R^2) per unit area, along the
    grain and along the bias alike (the stencils' plate has Poisson's ratio 0)."""
    net = rectangular_net(0.4, 0.4, 0.005)
    nodes, weights, scale = hinges(net)
    radius = 0.3
    energy = bending_energy(cylinder(net, radius, angle), nodes, weights, scale, B)
    assert energy == pytest.approx(B / (2 * radius**2) * 0.16, rel=0.015)


def test_a_cantilever_strip_converges_to_the_beam_solution():
    """Small deflection of a strip clamped at one end under its weight: tip drop W L^4 / (8 B)
    (linear beam theory), approached at first order in the spacing (the clamp's stencil)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as sla

    overhang, errors = 0.05, []
    for segments in (10, 20, 40):
        h = overhang / segments
        net = rectangular_net(overhang + 2 * h, 4 * h, h)
        u = net.uv[:, 0] - 2 * h
        nodes, weights, scale = hinges(net)
        n = net.node_count
        L = sp.csr_matrix(((B * scale[:, None, None] * weights[:, :, None] * weights[:, None, :]).ravel(),
                           (np.repeat(nodes, 4, axis=1).ravel(), np.tile(nodes, (1, 4)).ravel())), shape=(n, n))
        free = u > 1e-12
        load = net.node_areas()  # W = 1 N/m^2
        z = np.zeros(n)
        z[free] = sla.spsolve(L[free][:, free].tocsc(), -load[free])
        tip = -z[np.isclose(u, overhang)].mean()
        errors.append(tip / (overhang**4 / (8 * B)) - 1.0)
    assert errors[-1] < 0.06
    assert errors[1] / errors[2] == pytest.approx(2.0, rel=0.1)


def test_flat_cloth_in_any_pose_stores_no_bending_energy(rng):
    net = rectangular_net(0.2, 0.1, 0.01)
    nodes, weights, scale = hinges(net)
    rotation = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    pose = np.c_[net.uv, np.zeros(net.node_count)] @ rotation.T + rng.normal(size=3)
    assert bending_energy(pose, nodes, weights, scale, B) < 1e-18


def test_hinge_forces_are_minus_the_energy_gradient(rng):
    net = rectangular_net(0.06, 0.06, 0.02)
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    points = np.c_[net.uv, 0.003 * rng.normal(size=net.node_count)]
    b.add_cloth(net, library()["denim"], points)
    model = b.finalize("cpu")
    h = model.host
    forces = wp.zeros(model.node_count, dtype=wp.vec3, device="cpu")
    wp.launch(hinge_forces, dim=model.hinge_count,
              inputs=[model.node_rest_points, model.hinge_nodes, model.hinge_weights, model.hinge_stiffness, forces],
              device="cpu")

    def energy(p):
        k = np.einsum("hk,hkc->hc", h.hinge_weights, p[h.hinge_nodes])
        return 0.5 * np.sum(h.hinge_stiffness * np.sum(k * k, axis=1))

    gradient = np.zeros_like(points)
    step = 1e-6
    for i in range(net.node_count):
        for c in range(3):
            plus, minus = points.copy(), points.copy()
            plus[i, c] += step
            minus[i, c] -= step
            gradient[i, c] = (energy(plus) - energy(minus)) / (2 * step)
    assert np.allclose(forces.numpy(), -gradient, atol=1e-6 * np.abs(gradient).max())
    L = model.bending_matrix()
    assert 0.5 * np.sum(points * (L @ points)) == pytest.approx(energy(points), rel=1e-5)


def test_shear_diagonals_give_the_fabrics_shear_stiffness():
    """Simple shear by a small angle gamma stores G gamma^2 / 2 per unit area."""
    fabric = library()["cotton"].with_(bending_rigidity=0.0)
    net = rectangular_net(0.2, 0.1, 0.01)
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    gamma = 0.01
    b.add_cloth(net, fabric, np.c_[net.uv[:, 0] + gamma * net.uv[:, 1], net.uv[:, 1], np.zeros(net.node_count)])
    model = b.finalize("cpu")
    energy = total_energy(model, model.host.points)
    assert energy == pytest.approx(0.5 * fabric.shear * gamma**2 * 0.02, rel=0.02)


@pytest.mark.parametrize("poisson", [0.0, 0.3])
def test_membrane_strip_stretches_and_narrows_as_st_venant_kirchhoff_says(poisson):
    """A 1 m strip of a soft membrane fabric hanging from its top edge, relaxed with the
    implicit solver. Uniaxial St. Venant-Kirchhoff: at arc length s the stress resultant
    rho g (L - s) = (1 + e) E (e + e^2 / 2), so the strip lengthens by the integral of e; and
    the lateral Green strain is -nu E11, so at a quarter of the way down the width is
    w sqrt(1 - 2 nu E11)."""
    from scipy.optimize import brentq

    from party.solvers.relax import StaticRelaxation

    fabric = library()["knit_jersey"].with_(membrane=True, poisson=poisson, tensile_weft=24.9, shear=10.0,
                                            strain_limit=float("inf"), bending_rigidity=0.0)
    net = rectangular_net(1.0, 0.1, 0.02)  # warp vertical
    b = ModelBuilder()
    cloth = b.add_cloth(net, fabric, np.c_[np.zeros(net.node_count), net.uv[:, 1], -net.uv[:, 0]])
    b.pin(cloth.nodes(np.flatnonzero(net.uv[:, 0] == 0.0)))
    model = b.finalize("cpu")
    state = model.state()
    result = StaticRelaxation(model, collision=None, momentum=0.9, solver="implicit").relax(
        state, 1.0 / 300.0, max_iterations=4000, min_iterations=300, tolerance=1e-7)
    assert result.converged
    p = state.positions()
    load = fabric.areal_density * 9.80665 / fabric.tensile_warp

    def strain(s):
        return brentq(lambda e: (1 + e) * (e + e * e / 2) - load * (1.0 - s), 0.0, 1.0) if s < 1.0 else 0.0

    s = np.linspace(0.0, 1.0, 2001)
    expected = np.trapezoid([strain(x) for x in s], s)
    assert -p[:, 2].min() - 1.0 == pytest.approx(expected, rel=0.03)
    quarter = np.isclose(net.uv[:, 0], 0.24)
    width = p[quarter, 1].max() - p[quarter, 1].min()
    e11 = strain(0.24) + strain(0.24) ** 2 / 2
    assert width == pytest.approx(0.1 * np.sqrt(1 - 2 * poisson * e11), rel=0.005)


def test_explicit_solver_refuses_a_membrane():
    from party.errors import InvalidInput
    from party.solvers import SolverExplicit

    net = rectangular_net(0.1, 0.1, 0.02)
    b = ModelBuilder()
    b.add_cloth(net, library()["cotton"].with_(membrane=True), np.c_[net.uv, np.zeros(net.node_count)])
    with pytest.raises(InvalidInput, match="^the continuum membrane .* implicit solver only; use --solver implicit$"):
        SolverExplicit(b.finalize("cpu"))
