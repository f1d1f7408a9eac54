"""Every energy the implicit solver minimises, checked against finite differences.

A sweep of the implicit solver steps each node on its share of backward Euler's incremental
potential, G(d) = sum_i m_i / (2 dt^2) |d_i - y_i|^2 + E(x(t) + d) with the dampers'
c / (2 dt) |d_k - d_i|^2, from the gradient and Hessian block the solver computes
(:meth:`~party.solvers.implicit.SolverImplicit.node_steps`). Here G is written out in NumPy
(float64) for each term (springs, dampers, bending stencils, bending-hysteresis sliders, the
continuum membrane) and differentiated numerically: the gradient must match; the Hessian must
match where every term is in its exact regime (springs and membrane in tension, sliders stuck),
and bound it from above elsewhere (the solver projects each term's Hessian to be positive
semi-definite). The contact term, a body plane a node must stay outside, is checked as what
the sweep's step must be: the minimum of the node's quadratic model on the plane's outer side.
"""

import numpy as np
import pytest

from party.fabric import library
from party.meshing import rectangular_net
from party.model import ModelBuilder
from party.solvers.implicit import SolverImplicit

DT = 1.0 / 300.0
H_GRADIENT = 1.0e-6   # m, central differences of G for the gradient
H_HESSIAN = 1.0e-6    # m, for the Hessian: a slider's curvature moves by at most 0.03 1/m of its 0.05 1/m stuck range


def huber(r: np.ndarray, friction: float, limit: float) -> float:
    """The slider's energy of its return mapping: friction |r|^2 / 2 while friction |r| stays
    within ``limit``, then linear (:func:`party.solvers.hysteresis.slider_moment`)."""
    size = float(np.linalg.norm(r))
    if friction * size <= limit:
        return 0.5 * friction * size * size
    return limit * size - 0.5 * limit * limit / friction


def incremental_potential(model, x_start: np.ndarray, d: np.ndarray, y: np.ndarray, slip: np.ndarray) -> float:
    """G(d) [J] of the module docstring, term by term in float64."""
    h = model.host
    x = x_start + d
    inertia = 0.5 / DT**2 * float(np.sum(h.mass[:, None] * (d - y) ** 2))
    e = h.elements
    length = np.linalg.norm(x[e[:, 1]] - x[e[:, 0]], axis=1)
    springs = 0.5 * float(np.sum(h.element_stiffness * (length - h.element_rest_length) ** 2))
    dampers = 0.5 / DT * float(np.sum(h.element_damping[:, None] * (d[e[:, 1]] - d[e[:, 0]]) ** 2))
    bending = 0.5 * float(np.sum(x * (model.bending_matrix(friction=False) @ x)))
    sliders = 0.0
    limits = model.hinge_slip_limit.numpy().astype(float)
    for k in np.flatnonzero(h.hinge_friction > 0.0):
        curvature = h.hinge_weights[k] @ x[h.hinge_nodes[k]]
        sliders += huber(curvature - slip[k], float(h.hinge_friction[k]), float(limits[k]))
    membrane = 0.0
    inv_rest = model.triangle_inv_rest.numpy().astype(float)
    stiffness = model.triangle_membrane_c.numpy().astype(float)
    for t in np.flatnonzero(h.membrane_area > 0.0):
        a, b, c = h.triangles[t]
        f = np.column_stack([x[b] - x[a], x[c] - x[a]]) @ inv_rest[t]
        strain = np.array([0.5 * (f[:, 0] @ f[:, 0] - 1.0), 0.5 * (f[:, 1] @ f[:, 1] - 1.0), f[:, 0] @ f[:, 1]])
        membrane += h.membrane_area[t] * 0.5 * strain @ stiffness[t] @ strain
    return inertia + springs + dampers + bending + sliders + membrane


def numeric_gradient(model, x_start, d, y, slip, node: int) -> np.ndarray:
    grad = np.zeros(3)
    for a in range(3):
        plus, minus = d.copy(), d.copy()
        plus[node, a] += H_GRADIENT
        minus[node, a] -= H_GRADIENT
        grad[a] = (incremental_potential(model, x_start, plus, y, slip)
                   - incremental_potential(model, x_start, minus, y, slip)) / (2.0 * H_GRADIENT)
    return grad


def numeric_hessian(model, x_start, d, y, slip, node: int) -> np.ndarray:
    hess = np.zeros((3, 3))
    for a in range(3):
        for b in range(3):
            values = []
            for sa, sb in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
                moved = d.copy()
                moved[node, a] += sa * H_HESSIAN
                moved[node, b] += sb * H_HESSIAN
                values.append(sa * sb * incremental_potential(model, x_start, moved, y, slip))
            hess[a, b] = sum(values) / (4.0 * H_HESSIAN**2)
    return hess


FABRICS = {
    "springs and dampers": lambda: library()["cotton"].with_(bending_rigidity=0.0),
    "bending": lambda: library()["cotton"],
    "hysteresis sliders": lambda: library()["cotton"].with_(bending_hysteresis=2.0e-5),
    "membrane": lambda: library()["knit_jersey"].with_(membrane=True, poisson=0.3),
}


def patch(term: str):
    """A 4 x 4 patch of 1 cm net in the fabric that carries ``term``, its first row pinned, and
    the implicit solver for it."""
    net = rectangular_net(0.03, 0.03, 0.01)
    builder = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    builder.add_cloth(net, FABRICS[term](), np.c_[net.uv, np.zeros(net.node_count)])
    builder.pin(np.flatnonzero(net.uv[:, 1] < 1e-9))
    model = builder.finalize("cpu")
    return model, SolverImplicit(model, collision=None)


def curvatures(model, x: np.ndarray) -> np.ndarray:
    return np.einsum("hk,hkc->hc", model.host.hinge_weights, x[model.host.hinge_nodes])


@pytest.mark.parametrize("term", sorted(FABRICS))
@pytest.mark.parametrize("regime", ["exact", "projected"])
def test_a_sweeps_gradient_and_hessian_are_the_incremental_potentials(term, regime):
    """``exact``: the patch stretched 4 % with a wrinkle (springs and membrane in tension, the
    sliders stuck near their slip): gradient and Hessian block equal the finite differences.
    ``projected``: compressed 6 % with a larger wrinkle and the sliders slipping: the gradient
    still equal, the Hessian block the finite differences' plus a positive semi-definite part."""
    model, solver = patch(term)
    rng = np.random.default_rng(3)
    x_start = model.host.points.astype(float)
    centre = x_start.mean(axis=0)
    scale = 0.04 if regime == "exact" else -0.06
    d = scale * (x_start - centre) + rng.normal(0.0, 5e-5 if regime == "exact" else 2e-3, x_start.shape)
    y = d + rng.normal(0.0, 1e-4, d.shape)
    x = x_start + d
    offset = 1e-3 if regime == "exact" else 5.0
    slip = curvatures(model, x) + offset * rng.normal(size=(model.hinge_count, 3))
    grad, hess = solver.node_steps(x_start, d, y, DT, slip)
    if term == "hysteresis sliders":
        friction = model.host.hinge_friction
        limits = model.hinge_slip_limit.numpy()
        moments = friction[:, None] * np.linalg.norm(curvatures(model, x) - slip, axis=1)[:, None]
        stuck = moments[:, 0] <= limits
        assert stuck.all() if regime == "exact" else (~stuck).any()
    for node in np.flatnonzero(~model.host.kinematic):
        expected = numeric_gradient(model, x_start, d, y, slip, node)
        scale_g = np.abs(expected).max()
        assert np.abs(grad[node] - expected).max() <= 2e-3 * scale_g + 1e-6, (node, grad[node], expected)
        exact = numeric_hessian(model, x_start, d, y, slip, node)
        scale_h = np.abs(exact).max()
        if regime == "exact":
            assert np.abs(hess[node] - exact).max() <= 2e-3 * scale_h, (node, hess[node], exact)
        else:
            excess = np.linalg.eigvalsh(0.5 * (hess[node] - exact + (hess[node] - exact).T))
            assert excess.min() >= -2e-3 * scale_h, (node, excess)
            assert np.linalg.eigvalsh(hess[node]).min() > 0.0


def test_a_node_against_a_body_plane_steps_to_its_models_minimum_on_the_planes_outer_side():
    """The body plane inside the sweep: a node whose Newton step would end behind its plane
    ends on it, at the minimum of its quadratic model over the plane (tangential gradient of
    the model zero there, the plane pushing, not pulling); a node whose step ends in front is
    left its Newton step. The node is the last in the sweep's order, so it steps on the model
    at its neighbours' new displacements."""
    model, solver = patch("bending")
    rng = np.random.default_rng(5)
    x_start = model.host.points.astype(float)
    d = rng.normal(0.0, 5e-4, x_start.shape)
    d[model.host.kinematic] = 0.0
    y = d.copy()
    y[:, 2] -= 0.01  # every free node pulled 1 cm down
    node = int(np.flatnonzero(~model.host.kinematic)[-1])  # a corner of the free edge
    free = solver.descend_once(x_start, d, y, DT)
    before = free.copy()
    before[node] = d[node]
    grad, hess = solver.node_steps(x_start, before, y, DT)
    newton = -np.linalg.solve(hess[node], grad[node])
    assert np.allclose(free[node] - d[node], newton, rtol=1e-3, atol=1e-9)
    assert newton[2] < 0.0

    normal = np.zeros((model.node_count, 3))
    offset = np.zeros(model.node_count)
    normal[node] = (0.0, 0.0, 1.0)
    offset[node] = x_start[node, 2] + d[node, 2] + 0.5 * newton[2]  # halfway down the Newton step
    moved = solver.descend_once(x_start, d, y, DT, normal, offset)
    step = moved[node] - d[node]
    assert x_start[node, 2] + moved[node, 2] == pytest.approx(offset[node], abs=1e-8)
    model_gradient = grad[node] + hess[node] @ step  # of the quadratic model at the step's end
    assert np.abs(model_gradient[:2]).max() <= 1e-3 * np.abs(grad[node]).max()
    assert model_gradient[2] > 0.0  # the plane pushes the node out, it does not hold it in
