"""Kernels of the implicit solver: Vertex Block Descent on implicit Euler's incremental
potential (Chen, Macklin, Macklin, Yuksel, Kim: "Vertex Block Descent", SIGGRAPH 2024)."""

import warp as wp

from ...launch import worker_barrier
from ..explicit.kernels import stencil_curvature
from ..hysteresis import slider_moment


@wp.kernel
def inertial_target(
    x: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    f_ext: wp.array(dtype=wp.vec3),
    gravity: wp.vec3,
    kinematic_velocity: wp.array(dtype=wp.vec3),
    previous_correction: wp.array(dtype=wp.vec3),
    dt: float,
    y: wp.array(dtype=wp.vec3),
    x_iter: wp.array(dtype=wp.vec3),
):
    """y = x + v dt + (G + f_ext / m) dt^2, the position inertia alone would reach [m].

    The iterate starts at y, moved back against gravity by as much as the last solve moved the
    node back from its own y (between nothing and the whole of G dt^2; after Chen et al.'s
    adaptive start). A falling or sliding node starts at y, which is exact for it; a node the
    cloth holds up starts where it is. A solve cut short then leaves cloth at rest in
    equilibrium: starting every node at y leaves part of the weight's dt^2 push in each
    unfinished solve, and cloth held up by its own stiffness hangs as if heavier. Kinematic nodes move
    with the control's velocity and stay there."""
    i = wp.tid()
    if inv_mass[i] == 0.0:
        y[i] = x[i] + kinematic_velocity[i] * dt
        x_iter[i] = y[i]
    else:
        y[i] = x[i] + v[i] * dt + (gravity + f_ext[i] * inv_mass[i]) * dt * dt
        start = y[i]
        g = wp.length(gravity)
        if g > 0.0:
            down = gravity / g
            back = wp.clamp(wp.dot(previous_correction[i], down), -g * dt * dt, 0.0)
            start = start + back * down
        x_iter[i] = start


@wp.kernel
def record_correction(x: wp.array(dtype=wp.vec3), y: wp.array(dtype=wp.vec3), correction: wp.array(dtype=wp.vec3)):
    """The solve's correction x - y to the inertial target [m], for the next step's start."""
    i = wp.tid()
    correction[i] = x[i] - y[i]


@wp.struct
class MembraneTerms:
    force: wp.vec3
    hessian: wp.mat33


@wp.func
def membrane_gradient(x: wp.array(dtype=wp.vec3), tris: wp.array(dtype=int, ndim=2), d: wp.mat22, c: wp.mat33,
                      t: int, corner: int) -> MembraneTerms:
    """Per unit rest area, the gradient of a triangle's St. Venant-Kirchhoff membrane energy
    (E : C : E / 2, E the Green strain in the warp-aligned rest frame) with respect to one
    corner, and its Gauss-Newton Hessian block (positive semi-definite; the stress term only
    where the stress along that corner's shape gradient is tensile)."""
    x0 = x[tris[t, 0]]
    e1 = x[tris[t, 1]] - x0
    e2 = x[tris[t, 2]] - x0
    # F = [e1 e2] D, columns f0 (warp) and f1 (weft)
    f0 = e1 * d[0, 0] + e2 * d[1, 0]
    f1 = e1 * d[0, 1] + e2 * d[1, 1]
    strain = wp.vec3(0.5 * (wp.dot(f0, f0) - 1.0), 0.5 * (wp.dot(f1, f1) - 1.0), wp.dot(f0, f1))
    stress = c * strain  # S11, S22, S12
    # shape gradient of the corner: dF/dx_corner = I (x) g
    g = wp.vec2(-(d[0, 0] + d[1, 0]), -(d[0, 1] + d[1, 1]))
    if corner == 1:
        g = wp.vec2(d[0, 0], d[0, 1])
    elif corner == 2:
        g = wp.vec2(d[1, 0], d[1, 1])
    sg0 = stress[0] * g[0] + stress[2] * g[1]
    sg1 = stress[2] * g[0] + stress[1] * g[1]
    terms = MembraneTerms()
    terms.force = f0 * sg0 + f1 * sg1  # P g with P = F S
    # J: strain change (dE11, dE22, 2 dE12) per corner displacement, J = M F^T
    j = wp.matrix_from_rows(g[0] * f0, g[1] * f1, g[1] * f0 + g[0] * f1)
    geometric = wp.max(g[0] * sg0 + g[1] * sg1, 0.0)
    terms.hessian = wp.transpose(j) * c * j + geometric * wp.identity(n=3, dtype=float)
    return terms


@wp.struct
class DescentTerms:
    """What a node's block descent (:func:`descend_node`) reads besides the positions: the
    inertial targets ``y`` [m], masses [kg], each node's elements (``spring_*``), bending rows
    (``bend_*``), membrane triangles (``tri_*``, ``tris``, ``inv_rest``, ``membrane_*``) and
    bending-hysteresis sliders (``slider_*``, ``hinge_*``, ``slip_world``); set up once per solver."""

    y: wp.array(dtype=wp.vec3)
    mass: wp.array(dtype=float)
    inv_mass: wp.array(dtype=float)
    spring_offsets: wp.array(dtype=int)
    spring_other: wp.array(dtype=int)
    spring_params: wp.array(dtype=wp.vec3)
    bend_offsets: wp.array(dtype=int)
    bend_nodes: wp.array(dtype=int)
    bend_values: wp.array(dtype=float)
    tri_offsets: wp.array(dtype=int)
    tri_slots: wp.array(dtype=int)
    tris: wp.array(dtype=int, ndim=2)
    inv_rest: wp.array(dtype=wp.mat22)
    membrane_area: wp.array(dtype=float)
    membrane_c: wp.array(dtype=wp.mat33)
    slider_offsets: wp.array(dtype=int)
    slider_slots: wp.array(dtype=int)
    hinge_nodes: wp.array(dtype=wp.vec4i)
    hinge_weights: wp.array(dtype=wp.vec4)
    hinge_friction: wp.array(dtype=float)
    hinge_slip_limit: wp.array(dtype=float)
    slip_world: wp.array(dtype=wp.vec3)


@wp.func
def descend_node(i: int, terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), dt: float, x: wp.array(dtype=wp.vec3)):
    """One Newton step on one node's share of the incremental potential

        G_i(x_i) = m_i / (2 dt^2) |x_i - y_i|^2 + E_springs + E_dampers + E_hinges,

    the other nodes held (nodes of one colour share no element or hinge, so a colour runs in
    parallel). ``spring_*`` lists each node's elements: the other node and (l0 [m], k [N/m],
    c [kg/s]). Springs contribute k (l - l0) d and the Hessian k (d d^T + max(0, 1 - l0/l)
    (I - d d^T)) (projected to be positive semi-definite); the paper's dampers
    c (v_k - v_i) with v = (x - x(t)) / dt contribute c / dt I. The hinges' energy is the
    quadratic form x^T L x / 2 with the constant matrix L = sum_h stiffness_h K_h K_h^T
    (``bend_*``: row i of L, its diagonal included), so they add (L x)_i to the gradient and
    L_ii I to the Hessian. Membrane triangles add their St. Venant-Kirchhoff terms
    (:func:`membrane_gradient`). Bending hysteresis's elements (``slider_*``: each node's
    stencils with a slider, entries stencil * 4 + the node's corner) add K_i times their
    returned moment (:func:`~party.solvers.hysteresis.slider_moment`, with c_slip at the
    step's start in ``slip_world``) and friction K_i^2 I, a bound on their Hessian.
    """
    if terms.inv_mass[i] == 0.0:
        return
    xi = x[i]
    h2 = dt * dt
    m = terms.mass[i]
    grad = (m / h2) * (xi - terms.y[i])
    hess = (m / h2) * wp.identity(n=3, dtype=float)
    vi = xi - x_start[i]
    diagonal = float(0.0)
    for j in range(terms.spring_offsets[i], terms.spring_offsets[i + 1]):
        k = terms.spring_other[j]
        p = terms.spring_params[j]
        xk = x[k]
        d = xk - xi
        length = wp.length(d)
        if length > 1.0e-12:
            u = d / length
            grad -= p[1] * (length - p[0]) * u
            slack = wp.max(0.0, 1.0 - p[0] / length)
            hess += (p[1] * (1.0 - slack)) * wp.outer(u, u)
            diagonal += p[1] * slack
        c = p[2] / dt
        grad -= c * ((xk - x_start[k]) - vi)
        diagonal += c
    for j in range(terms.bend_offsets[i], terms.bend_offsets[i + 1]):
        k = terms.bend_nodes[j]
        grad += terms.bend_values[j] * x[k]
        if k == i:
            diagonal += terms.bend_values[j]
    for j in range(terms.tri_offsets[i], terms.tri_offsets[i + 1]):
        slot = terms.tri_slots[j]
        t = slot // 3
        area = terms.membrane_area[t]
        if area > 0.0:
            g = membrane_gradient(x, terms.tris, terms.inv_rest[t], terms.membrane_c[t], t, slot - 3 * t)
            grad += area * g.force
            hess += area * g.hessian
    for j in range(terms.slider_offsets[i], terms.slider_offsets[i + 1]):
        slot = terms.slider_slots[j]
        h = slot // 4
        weight = terms.hinge_weights[h][slot - 4 * h]
        friction = terms.hinge_friction[h]
        curvature = stencil_curvature(x, terms.hinge_nodes[h], terms.hinge_weights[h])
        grad += weight * slider_moment(curvature, terms.slip_world[h], friction, terms.hinge_slip_limit[h])
        diagonal += friction * weight * weight
    hess += diagonal * wp.identity(n=3, dtype=float)
    det = wp.determinant(hess)
    if det > 1.0e-20:
        x[i] = xi - wp.inverse(hess) * grad


@wp.kernel
def block_descent(first: int, colored: wp.array(dtype=int), terms: DescentTerms, x_start: wp.array(dtype=wp.vec3),
                  dt: float, x: wp.array(dtype=wp.vec3)):
    """:func:`descend_node` for the nodes ``colored[first + tid]`` (one colour)."""
    descend_node(colored[first + wp.tid()], terms, x_start, dt, x)


@wp.kernel
def sweep_workers(worker: int, workers: int, sync: wp.array(dtype=int), max_spins: int, iterations: int,
                  color_offsets: wp.array(dtype=int), omegas: wp.array(dtype=float), colored: wp.array(dtype=int),
                  terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), dt: float, x: wp.array(dtype=wp.vec3),
                  x_previous: wp.array(dtype=wp.vec3), x_before: wp.array(dtype=wp.vec3)):
    """All of a step's sweeps as one worker of :func:`~party.launch.launch_workers`: the worker
    takes its share of each colour's nodes (:func:`descend_node`) and of the Chebyshev blend
    (``omegas[k]`` of sweep k; none where ``omegas`` is empty), the workers meeting between
    them. Each node's arithmetic is that of :func:`block_descent` and :func:`chebyshev_blend`,
    so the result is bit for bit that of the launches one colour at a time."""
    for iteration in range(iterations):
        for c in range(color_offsets.shape[0] - 1):
            first = color_offsets[c]
            count = color_offsets[c + 1] - first
            for j in range(first + count * worker // workers, first + count * (worker + 1) // workers):
                descend_node(colored[j], terms, x_start, dt, x)
            worker_barrier(sync, workers, max_spins)
        if omegas.shape[0] > 0:
            n = x.shape[0]
            for i in range(n * worker // workers, n * (worker + 1) // workers):
                if iteration == 0:
                    x_previous[i] = x[i]
                else:
                    blend_node(i, x, x_previous, x_before, omegas[iteration])
            worker_barrier(sync, workers, max_spins)


@wp.kernel
def step_velocity(x_start: wp.array(dtype=wp.vec3), x_end: wp.array(dtype=wp.vec3), dt: float,
                  x_out: wp.array(dtype=wp.vec3), v_out: wp.array(dtype=wp.vec3)):
    """v* = (x_end - x(t)) / dt, and x_out = x(t) for the collision pass and eq. (4)."""
    i = wp.tid()
    x_out[i] = x_start[i]
    v_out[i] = (x_end[i] - x_start[i]) / dt


@wp.kernel
def chebyshev_blend(x: wp.array(dtype=wp.vec3), previous: wp.array(dtype=wp.vec3), before: wp.array(dtype=wp.vec3),
                    omega: float):
    """Chebyshev semi-iterative acceleration of the sweeps (Wang 2015; used by VBD):
    :func:`blend_node` for every node."""
    blend_node(wp.tid(), x, previous, before, omega)


@wp.func
def blend_node(i: int, x: wp.array(dtype=wp.vec3), previous: wp.array(dtype=wp.vec3),
               before: wp.array(dtype=wp.vec3), omega: float):
    """x_k <- omega (x_k - x_{k-2}) + x_{k-2}; then shift the history (``previous`` = x_{k-1}
    becomes x_{k-2} in ``before``, and x_k becomes ``previous``)."""
    xk = omega * (x[i] - before[i]) + before[i]
    x[i] = xk
    before[i] = previous[i]
    previous[i] = xk
