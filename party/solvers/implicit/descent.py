"""A node's Vertex Block Descent step on implicit Euler's incremental potential (Chen, Macklin,
Macklin, Yuksel, Kim: "Vertex Block Descent", SIGGRAPH 2024), and the kernels that sweep it.

The kernels come in two builds (:data:`DESCENT`, :func:`descent_kernels`): one for a net of
springs and hinges alone, and one that also reads membrane triangles and bending-hysteresis
sliders (:func:`extra_terms`). A net without them sweeps faster in its own build than in one that
skips their empty rows at run time.
"""

from typing import NamedTuple

import warp as wp

from ...launch import WorkerSync, worker_barrier
from ..hysteresis import slider_moment

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

PLANE_CONTACT = wp.constant(1.0e-4)
"""How far [m] above its body plane a node still counts as resting on it (``plane_reactions``):
the sweeps leave a node the plane held a few microns off it, and a node given no reaction is
given no friction either."""


@wp.func
def moved_from(x_start: wp.array(dtype=wp.vec3), disp: wp.array(dtype=wp.vec3), k: int, xi: wp.vec3,
               di: wp.vec3) -> wp.vec3:
    """x_k - x_i at the iterate, (x_k(t) - x_i(t)) + (d_k - d_i) [m], with node i's start ``xi``
    and displacement ``di`` read once for all its neighbours k: both differences of nearby
    numbers, so that neither loses a displacement to a position's round-off."""
    return (x_start[k] - xi) + (disp[k] - di)


@wp.func
def moved(x_start: wp.array(dtype=wp.vec3), disp: wp.array(dtype=wp.vec3), k: int, i: int) -> wp.vec3:
    """:func:`moved_from` for node i read from the arrays."""
    return moved_from(x_start, disp, k, x_start[i], disp[i])


@wp.func
def moved_curvature(x_start: wp.array(dtype=wp.vec3), disp: wp.array(dtype=wp.vec3), n: wp.vec4i,
                    w: wp.vec4) -> wp.vec3:
    """A bending stencil's curvature vector sum_i K_i x_i at the iterate [1/m], as
    sum_i K_i (x_i - x_0) (the weights sum to zero; :mod:`party.meshing.hinges`)."""
    return (w[1] * moved(x_start, disp, n[1], n[0]) + w[2] * moved(x_start, disp, n[2], n[0])
            + w[3] * moved(x_start, disp, n[3], n[0]))


@wp.struct
class MembraneTerms:
    force: wp.vec3
    hessian: wp.mat33


@wp.func
def membrane_gradient(x_start: wp.array(dtype=wp.vec3), disp: wp.array(dtype=wp.vec3),
                      tris: wp.array(dtype=int, ndim=2), d: wp.mat22, c: wp.mat33, t: int,
                      corner: int) -> MembraneTerms:
    """Per unit rest area, the gradient of a triangle's St. Venant-Kirchhoff membrane energy
    (E : C : E / 2, E the Green strain in the warp-aligned rest frame) with respect to one
    corner, and its Gauss-Newton Hessian block (positive semi-definite; the stress term only
    where the stress along that corner's shape gradient is tensile), at x(t) + ``disp``."""
    e1 = moved(x_start, disp, tris[t, 1], tris[t, 0])
    e2 = moved(x_start, disp, tris[t, 2], tris[t, 0])
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
    """What a node's block descent (``descend_node`` of :func:`descent_kernels`) reads besides
    the positions: the inertial targets ``y`` [m], masses [kg], each node's neighbours through
    its elements and bending row (``neighbour_*``, ``bend_diagonal``: the solver's
    ``NeighbourRows``), membrane triangles (``tri_*``, ``tris``,
    ``inv_rest``, ``membrane_*``) and bending-hysteresis sliders (``slider_*``, ``hinge_*``,
    ``slip_world``); set up once per solver."""

    y: wp.array(dtype=wp.vec3)
    mass: wp.array(dtype=float)
    inv_mass: wp.array(dtype=float)
    neighbour_offsets: wp.array(dtype=int)
    neighbour_nodes: wp.array(dtype=int)
    neighbour_params: wp.array(dtype=wp.vec4)
    bend_diagonal: wp.array(dtype=float)
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
    plane_normal: wp.array(dtype=wp.vec3)
    plane_offset: wp.array(dtype=float)
    plane_push: wp.array(dtype=wp.vec3)


@wp.struct
class NodeStep:
    """A node's gradient [N] and Hessian block [N/m] of the incremental potential at the iterate."""
    grad: wp.vec3
    hess: wp.mat33


@wp.func
def extra_terms(i: int, terms: DescentTerms, x_start: wp.array(dtype=wp.vec3),
                disp: wp.array(dtype=wp.vec3)) -> NodeStep:
    """Node i's gradient [N] and Hessian block [N/m] from its membrane triangles and
    bending-hysteresis sliders (see :data:`DESCENT`)."""
    grad = wp.vec3()
    hess = wp.mat33()
    diagonal = float(0.0)
    for j in range(terms.tri_offsets[i], terms.tri_offsets[i + 1]):
        slot = terms.tri_slots[j]
        t = slot // 3
        area = terms.membrane_area[t]
        if area > 0.0:
            g = membrane_gradient(x_start, disp, terms.tris, terms.inv_rest[t], terms.membrane_c[t], t, slot - 3 * t)
            grad += area * g.force
            hess += area * g.hessian
    for j in range(terms.slider_offsets[i], terms.slider_offsets[i + 1]):
        slot = terms.slider_slots[j]
        h = slot // 4
        weight = terms.hinge_weights[h][slot - 4 * h]
        friction = terms.hinge_friction[h]
        curvature = moved_curvature(x_start, disp, terms.hinge_nodes[h], terms.hinge_weights[h])
        grad += weight * slider_moment(curvature, terms.slip_world[h], friction, terms.hinge_slip_limit[h])
        diagonal += friction * weight * weight
    result = NodeStep()
    result.grad = grad
    result.hess = hess + diagonal * wp.identity(n=3, dtype=float)
    return result


@wp.func
def behind_plane(terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), i: int, d: wp.vec3) -> float:
    """How far [m] node i at displacement ``d`` lies behind its body plane (negative: in front;
    0 for a node without one)."""
    n = terms.plane_normal[i]
    return terms.plane_offset[i] - wp.dot(x_start[i], n) - wp.dot(d, n)


@wp.func
def blend_node(i: int, x: wp.array(dtype=wp.vec3), previous: wp.array(dtype=wp.vec3),
               before: wp.array(dtype=wp.vec3), omega: float, plane_normal: wp.array(dtype=wp.vec3)):
    """x_k <- omega (x_k - x_{k-2}) + x_{k-2}; then shift the history (``previous`` = x_{k-1}
    becomes x_{k-2} in ``before``, and x_k becomes ``previous``). Along the normal of a node's
    body plane (:func:`~.kernels.body_planes`) x_k is kept as the sweep left it: extrapolated, a
    node that a sweep brought onto the plane from behind it would leave the plane outwards, lose
    its contact and its friction, and fall back in the next step."""
    xk = omega * (x[i] - before[i]) + before[i]
    n = plane_normal[i]
    xk += wp.dot(x[i] - xk, n) * n
    x[i] = xk
    before[i] = previous[i]
    previous[i] = xk


class DescentKernels(NamedTuple):
    """One build of the descent's kernels (see the module docstring)."""

    node_steps: wp.Kernel
    plane_reactions: wp.Kernel
    block_descent: wp.Kernel
    sweep_workers: wp.Kernel


def descent_kernels(with_extra: bool) -> DescentKernels:
    """The descent's kernels, reading membrane triangles and sliders where ``with_extra``."""
    suffix = "extra" if with_extra else "net"

    @wp.func(name=f"node_terms_{suffix}")
    def node_terms(i: int, terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), dt: float,
                   disp: wp.array(dtype=wp.vec3)) -> NodeStep:
        """The gradient and Hessian block that ``descend_node`` steps on."""
        xi = x_start[i]
        di = disp[i]
        inv_dt = 1.0 / dt
        inertia = terms.mass[i] * inv_dt * inv_dt
        grad = inertia * (di - terms.y[i])
        hess = inertia * wp.identity(n=3, dtype=float)
        diagonal = float(terms.bend_diagonal[i])
        for j in range(terms.neighbour_offsets[i], terms.neighbour_offsets[i + 1]):
            k = terms.neighbour_nodes[j]
            p = terms.neighbour_params[j]
            moved_k = disp[k] - di
            d = (x_start[k] - xi) + moved_k
            grad += p[3] * d
            if p[1] != 0.0:
                length = wp.length(d)
                if length > 1.0e-12:
                    inv_length = 1.0 / length
                    u = d * inv_length
                    grad -= p[1] * (length - p[0]) * u
                    slack = wp.max(0.0, 1.0 - p[0] * inv_length)
                    hess += (p[1] * (1.0 - slack)) * wp.outer(u, u)
                    diagonal += p[1] * slack
            c = p[2] * inv_dt
            grad -= c * moved_k
            diagonal += c
        if wp.static(with_extra):
            extra = extra_terms(i, terms, x_start, disp)
            grad += extra.grad
            hess += extra.hess
        hess += diagonal * wp.identity(n=3, dtype=float)
        result = NodeStep()
        result.grad = grad
        result.hess = hess
        return result

    @wp.func(name=f"descend_node_{suffix}")
    def descend_node(i: int, terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), dt: float,
                     disp: wp.array(dtype=wp.vec3)):
        """One Newton step on one node's share of the incremental potential, in the node's
        displacement d_i = x_i - x_i(t) (``disp``; see :func:`~.kernels.inertial_target`),

            G_i(d_i) = m_i / (2 dt^2) |d_i - y_i|^2 + E_springs + E_dampers + E_hinges,

        the other nodes held (nodes of one colour share no element or hinge, so a colour runs in
        parallel). ``neighbour_*`` lists each node's neighbours once, each with its element's
        (l0 [m], k [N/m], c [kg/s]) and its bending entry L_ij (zeros where there is none; the
        solver's ``NeighbourRows``). Springs contribute k (l - l0) d and the Hessian
        k (d d^T + max(0, 1 - l0/l) (I - d d^T)) (projected to be positive semi-definite); the
        paper's dampers c (v_k - v_i) with v = (x - x(t)) / dt contribute c / dt I. The hinges'
        energy is the quadratic form x^T L x / 2 with the constant matrix L = sum_h stiffness_h
        K_h K_h^T (its rows sum to zero; L_ii in ``bend_diagonal``), so they add
        (L x)_i = sum_j L_ij (x_j - x_i) to the gradient and L_ii I to the Hessian. Membrane
        triangles add their St. Venant-Kirchhoff terms (:func:`membrane_gradient`). Bending
        hysteresis's elements (``slider_*``: each node's stencils with a slider, entries stencil * 4
        + the node's corner) add K_i times their returned moment
        (:func:`~party.solvers.hysteresis.slider_moment`, with c_slip at the step's start in
        ``slip_world``) and friction K_i^2 I, a bound on their Hessian.

        A node that the last Collision() found against the body steps to the minimum of its
        quadratic model on the outer side of that face's plane (``plane_*``,
        :func:`~.kernels.body_planes`): the Newton step, moved along H^-1 n until n . x reaches
        the plane where it ended behind it (``plane_reactions`` gives the plane's reaction after
        the sweeps).
        """
        if terms.inv_mass[i] == 0.0:
            return
        step = node_terms(i, terms, x_start, dt, disp)
        grad = step.grad
        hess = step.hess
        di = disp[i]
        det = wp.determinant(hess)
        if det > 1.0e-20:
            inverse = wp.inverse(hess)
            d_new = di - inverse * grad
            n = terms.plane_normal[i]
            gap = behind_plane(terms, x_start, i, d_new)
            if wp.length_sq(n) > 0.0 and gap > 0.0:
                d_new += (gap / wp.dot(n, inverse * n)) * (inverse * n)
            disp[i] = d_new

    @wp.kernel(name=f"node_steps_{suffix}")
    def node_steps(terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), dt: float, disp: wp.array(dtype=wp.vec3),
                   grad: wp.array(dtype=wp.vec3), hess: wp.array(dtype=wp.mat33)):
        """Every node's gradient [N] and Hessian block [N/m] of the incremental potential, as
        ``descend_node`` steps on them (for checks against finite differences)."""
        i = wp.tid()
        step = node_terms(i, terms, x_start, dt, disp)
        grad[i] = step.grad
        hess[i] = step.hess

    @wp.kernel(name=f"plane_reactions_{suffix}")
    def plane_reactions(terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), dt: float,
                        disp: wp.array(dtype=wp.vec3)):
        """The reaction of each node's body plane at the solve's end, lambda = n . grad G_i [N]
        where the node lies on the plane (within :data:`PLANE_CONTACT`) and grad G_i presses it
        into the plane (a node held by the plane at the minimum has grad G_i = lambda n; over a
        uniformly pressed patch the lambdas sum to its weight's normal part, the internal forces
        cancelling), as the velocity lambda dt / m along n that it gave the node, into
        ``plane_push``, for the body response's friction
        (:func:`~party.collision.body.collide_body`)."""
        i = wp.tid()
        n = terms.plane_normal[i]
        if terms.inv_mass[i] == 0.0 or wp.length_sq(n) == 0.0:
            return
        gap = behind_plane(terms, x_start, i, disp[i])
        if gap < -PLANE_CONTACT:
            return
        reaction = wp.max(wp.dot(n, node_terms(i, terms, x_start, dt, disp).grad), 0.0)
        terms.plane_push[i] = (reaction * dt / terms.mass[i]) * n

    @wp.kernel(name=f"block_descent_{suffix}")
    def block_descent(first: int, colored: wp.array(dtype=int), terms: DescentTerms, x_start: wp.array(dtype=wp.vec3),
                      dt: float, disp: wp.array(dtype=wp.vec3)):
        """``descend_node`` for the nodes ``colored[first + tid]`` (one colour)."""
        descend_node(colored[first + wp.tid()], terms, x_start, dt, disp)

    @wp.kernel(name=f"sweep_workers_{suffix}")
    def sweep_workers(worker: int, workers: int, sync: WorkerSync, iterations: int,
                      color_offsets: wp.array(dtype=int), omegas: wp.array(dtype=float), colored: wp.array(dtype=int),
                      terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), dt: float, disp: wp.array(dtype=wp.vec3),
                      disp_previous: wp.array(dtype=wp.vec3), disp_before: wp.array(dtype=wp.vec3)):
        """All of a step's sweeps as one worker of :func:`~party.launch.launch_workers`: the worker
        takes its share of each colour's nodes (``descend_node``) and of the Chebyshev blend
        (``omegas[k]`` of sweep k; none where ``omegas`` is empty), the workers meeting between
        them. Each node's arithmetic is that of ``block_descent`` and
        :func:`~.kernels.chebyshev_blend`, so the result is bit for bit that of the launches one
        colour at a time."""
        for iteration in range(iterations):
            for c in range(color_offsets.shape[0] - 1):
                first = color_offsets[c]
                count = color_offsets[c + 1] - first
                for j in range(first + count * worker // workers, first + count * (worker + 1) // workers):
                    descend_node(colored[j], terms, x_start, dt, disp)
                worker_barrier(sync, workers)
            if omegas.shape[0] > 0:
                n = disp.shape[0]
                for i in range(n * worker // workers, n * (worker + 1) // workers):
                    if iteration == 0:
                        disp_previous[i] = disp[i]
                    else:
                        blend_node(i, disp, disp_previous, disp_before, omegas[iteration], terms.plane_normal)
                worker_barrier(sync, workers)

    return DescentKernels(node_steps, plane_reactions, block_descent, sweep_workers)


DESCENT = {False: descent_kernels(False), True: descent_kernels(True)}
"""The two builds, by whether the model has membrane triangles or sliders."""
