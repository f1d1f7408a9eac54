"""Kernels of the implicit solver: Vertex Block Descent on implicit Euler's incremental
potential (Chen, Macklin, Macklin, Yuksel, Kim: "Vertex Block Descent", SIGGRAPH 2024)."""

import warp as wp

from ...collision.geometry import closest_point_barycentric, interpolate
from ...launch import WorkerSync, worker_barrier
from ..hysteresis import slider_moment

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels


@wp.kernel
def inertial_target(
    x: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    f_ext: wp.array(dtype=wp.vec3),
    gravity: wp.vec3,
    kinematic_velocity: wp.array(dtype=wp.vec3),
    previous_correction: wp.array(dtype=wp.vec3),
    plane_normal: wp.array(dtype=wp.vec3),
    dt: float,
    y: wp.array(dtype=wp.vec3),
    disp: wp.array(dtype=wp.vec3),
):
    """y = v dt + (G + f_ext / m) dt^2, the step inertia alone would take the node [m], and
    the sweeps' starting displacement ``disp``.

    The solve works on the step's displacements d = x - x(t), not on positions: a sweep's
    correction to a node is often below the round-off of a single-precision position (2e-9 m
    at 3 cm, 6e-8 m at 1 m), and would be lost; a displacement resolves it. A cotton
    cantilever of 0.6 mm segments stalled with its chord at 43.6 degrees at 3 cm from the
    origin and at 65.6 degrees at 1 m, against 42.4 at rest; it now rests at 42.4 (43.1 at
    1 m, where the state's own round-off jitters it; see docs/design.md).

    The iterate starts at y, moved back against gravity by as much as the last solve moved the
    node back from its own y (between nothing and the whole of G dt^2; after Chen et al.'s
    adaptive start). A falling or sliding node starts at y, which is exact for it; a node the
    cloth holds up starts where it is. A solve cut short then leaves cloth at rest in
    equilibrium: starting every node at y leaves part of the weight's dt^2 push in each
    unfinished solve, and cloth held up by its own stiffness hangs as if heavier. A node held
    by a body plane (:func:`body_planes`) starts at y: the plane holds it, and on a slope a
    start moved back along gravity would also hold back its slide, which the sweeps, stiff in
    the cloth's plane, do not restore within a step (a patch on a 40 degree slope of mu 0.6
    slid 6 % slower than g (sin - mu cos)). Kinematic nodes move with the control's velocity
    and stay there."""
    i = wp.tid()
    if inv_mass[i] == 0.0:
        y[i] = kinematic_velocity[i] * dt
        disp[i] = y[i]
    else:
        y[i] = v[i] * dt + (gravity + f_ext[i] * inv_mass[i]) * dt * dt
        start = y[i]
        g = wp.length(gravity)
        if g > 0.0 and wp.length_sq(plane_normal[i]) == 0.0:
            down = gravity / g
            back = wp.clamp(wp.dot(previous_correction[i], down), -g * dt * dt, 0.0)
            start = start + back * down
        disp[i] = start


PLANE_CONTACT = wp.constant(1.0e-4)
"""How far [m] above its body plane a node still counts as resting on it (:func:`plane_reactions`):
the sweeps leave a node the plane held a few microns off it, and a node given no reaction is
given no friction either."""


@wp.func
def face_point(x: wp.vec3, f: int, faces: wp.array(dtype=int, ndim=2), body_q: wp.array(dtype=wp.vec3)) -> wp.vec3:
    """The point of body face ``f`` nearest ``x`` [m]."""
    a = body_q[faces[f, 0]]
    b = body_q[faces[f, 1]]
    c = body_q[faces[f, 2]]
    return interpolate(closest_point_barycentric(x, a, b, c), a, b, c)


@wp.func
def nearest_candidate(x: wp.vec3, f: int, faces: wp.array(dtype=int, ndim=2), body_q: wp.array(dtype=wp.vec3),
                      candidates: wp.array(dtype=int, ndim=2), candidate_count: wp.array(dtype=int), i: int) -> int:
    """Of face ``f`` and node i's candidate faces, the one whose nearest point lies nearest ``x``
    (``f`` where none is nearer)."""
    best = f
    best_distance = wp.length(x - face_point(x, f, faces, body_q))
    for j in range(candidate_count[i]):
        g = candidates[i, j]
        distance = wp.length(x - face_point(x, g, faces, body_q))
        if distance < best_distance:
            best = g
            best_distance = distance
    return best


@wp.kernel
def body_planes(first: int, contact_face: wp.array(dtype=int), faces: wp.array(dtype=int, ndim=2),
                body_q: wp.array(dtype=wp.vec3), body_qd: wp.array(dtype=wp.vec3), x: wp.array(dtype=wp.vec3),
                thickness: wp.array(dtype=float), candidates: wp.array(dtype=int, ndim=2),
                candidate_count: wp.array(dtype=int), dt: float, normal: wp.array(dtype=wp.vec3),
                offset: wp.array(dtype=float), push: wp.array(dtype=wp.vec3)):
    """The plane each node must stay on the outer side of over this step (ours; VBD puts its
    contacts in the solve likewise): n . x >= offset, where the last Collision() found the node
    in contact with a body face. It is the plane tangent to the surface eps [m] off the body
    where the node starts the step, taken from the face nearest the node among that face and
    the node's candidates (``candidates``, ``candidate_count``): n points from the face's point
    nearest the node to the node (the face's normal where the node lies over the face, or
    behind it), and offset is n . p + eps with p that point moved by the body's velocity over
    the step. Over a rim or an edge, n turns round it with the node, so that the plane does not
    hold a node that has left the face out over the face's extension. n = 0 where it found none.
    Clears ``push`` (item-wise: node i writes only its own).

    The contact face itself may be a neighbour of the face the node lies over: over a convex
    body a neighbour's plane passes above the node's own face, and the response
    (:func:`~party.collision.body.collide_body`) takes the face whose plane the node reached
    first, within a quarter of eps beside it. A node resting there took the one face on one
    step and the other on the next, and the plane of the face beside it, turned round that
    face's edge, lifted it: on the sphere drop at 1/150 s, 21 nodes rocked by 0.2 to 0.65 mm
    at every step (none with the nearest face)."""
    i = first + wp.tid()
    push[i] = wp.vec3(0.0)
    f = contact_face[i]
    if f < 0:
        normal[i] = wp.vec3(0.0)
        offset[i] = 0.0
        return
    f = nearest_candidate(x[i], f, faces, body_q, candidates, candidate_count, i)
    a = body_q[faces[f, 0]]
    b = body_q[faces[f, 1]]
    c = body_q[faces[f, 2]]
    w = closest_point_barycentric(x[i], a, b, c)
    p = interpolate(w, a, b, c)
    n = wp.normalize(wp.cross(b - a, c - a))
    away = x[i] - p
    if wp.dot(away, n) > 0.0 and wp.length(away) > 0.0:
        n = wp.normalize(away)
    if wp.length(away) > 2.0 * thickness[i]:
        contact_face[i] = -1
        normal[i] = wp.vec3(0.0)
        offset[i] = 0.0
        return
    vb = interpolate(w, body_qd[faces[f, 0]], body_qd[faces[f, 1]], body_qd[faces[f, 2]])
    normal[i] = n
    offset[i] = wp.dot(p + vb * dt, n) + thickness[i]


@wp.func
def moved(x_start: wp.array(dtype=wp.vec3), disp: wp.array(dtype=wp.vec3), k: int, i: int) -> wp.vec3:
    """x_k - x_i at the iterate, (x_k(t) - x_i(t)) + (d_k - d_i) [m]: both differences of
    nearby numbers, so that neither loses a displacement to a position's round-off."""
    return (x_start[k] - x_start[i]) + (disp[k] - disp[i])


@wp.func
def moved_from(x_start: wp.array(dtype=wp.vec3), disp: wp.array(dtype=wp.vec3), k: int, xi: wp.vec3,
               di: wp.vec3) -> wp.vec3:
    """:func:`moved` with node i's start ``xi`` and displacement ``di`` [m] read once for all
    its neighbours k."""
    return (x_start[k] - xi) + (disp[k] - di)


@wp.func
def moved_curvature(x_start: wp.array(dtype=wp.vec3), disp: wp.array(dtype=wp.vec3), n: wp.vec4i,
                    w: wp.vec4) -> wp.vec3:
    """A bending stencil's curvature vector sum_i K_i x_i at the iterate [1/m], as
    sum_i K_i (x_i - x_0) (the weights sum to zero; :mod:`party.meshing.hinges`)."""
    return (w[1] * moved(x_start, disp, n[1], n[0]) + w[2] * moved(x_start, disp, n[2], n[0])
            + w[3] * moved(x_start, disp, n[3], n[0]))


@wp.kernel
def record_correction(disp: wp.array(dtype=wp.vec3), y: wp.array(dtype=wp.vec3), push: wp.array(dtype=wp.vec3),
                      dt: float, correction: wp.array(dtype=wp.vec3)):
    """The solve's correction d - y to the inertial target [m], for the next step's start, less
    what a body plane's reaction gave it (``push`` [m/s] over ``dt``): a node that leaves the
    body starts from where the cloth, not the body, held it."""
    i = wp.tid()
    correction[i] = disp[i] - y[i] - push[i] * dt


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
    """What a node's block descent (:func:`descend_node`) reads besides the positions: the
    inertial targets ``y`` [m], masses [kg], each node's elements (``spring_*``), bending rows
    (``bend_*``), membrane triangles (``tri_*``, ``tris``, ``inv_rest``, ``membrane_*``) and
    bending-hysteresis sliders (``slider_*``, ``hinge_*``, ``slip_world``); set up once per solver.
    ``has_extra`` is 0 where the model has neither membrane triangles nor sliders
    (:func:`extra_terms`)."""

    y: wp.array(dtype=wp.vec3)
    mass: wp.array(dtype=float)
    inv_mass: wp.array(dtype=float)
    spring_offsets: wp.array(dtype=int)
    spring_other: wp.array(dtype=int)
    spring_params: wp.array(dtype=wp.vec3)
    bend_offsets: wp.array(dtype=int)
    bend_nodes: wp.array(dtype=int)
    bend_values: wp.array(dtype=float)
    has_extra: int
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


@wp.func(inline=False)
def extra_terms(i: int, terms: DescentTerms, x_start: wp.array(dtype=wp.vec3),
                disp: wp.array(dtype=wp.vec3)) -> NodeStep:
    """Node i's gradient [N] and Hessian block [N/m] from its membrane triangles and
    bending-hysteresis sliders (see :func:`descend_node`). Out of line and called only where
    the model has either: inlined, their loops slowed every node's descent in a net of springs
    and hinges alone by some 8 %, empty as they were."""
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
def node_terms(i: int, terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), dt: float,
               disp: wp.array(dtype=wp.vec3)) -> NodeStep:
    """The gradient and Hessian block that :func:`descend_node` steps on."""
    xi = x_start[i]
    di = disp[i]
    inv_dt = 1.0 / dt
    inertia = terms.mass[i] * inv_dt * inv_dt
    grad = inertia * (di - terms.y[i])
    hess = inertia * wp.identity(n=3, dtype=float)
    diagonal = float(0.0)
    for j in range(terms.spring_offsets[i], terms.spring_offsets[i + 1]):
        k = terms.spring_other[j]
        p = terms.spring_params[j]
        d = moved_from(x_start, disp, k, xi, di)
        length = wp.length(d)
        if length > 1.0e-12:
            inv_length = 1.0 / length
            u = d * inv_length
            grad -= p[1] * (length - p[0]) * u
            slack = wp.max(0.0, 1.0 - p[0] * inv_length)
            hess += (p[1] * (1.0 - slack)) * wp.outer(u, u)
            diagonal += p[1] * slack
        c = p[2] * inv_dt
        grad -= c * (disp[k] - di)
        diagonal += c
    for j in range(terms.bend_offsets[i], terms.bend_offsets[i + 1]):
        k = terms.bend_nodes[j]
        if k == i:
            diagonal += terms.bend_values[j]
        else:
            grad += terms.bend_values[j] * moved_from(x_start, disp, k, xi, di)
    if terms.has_extra != 0:
        extra = extra_terms(i, terms, x_start, disp)
        grad += extra.grad
        hess += extra.hess
    hess += diagonal * wp.identity(n=3, dtype=float)
    result = NodeStep()
    result.grad = grad
    result.hess = hess
    return result


@wp.func
def behind_plane(terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), i: int, d: wp.vec3) -> float:
    """How far [m] node i at displacement ``d`` lies behind its body plane (negative: in front;
    0 for a node without one)."""
    n = terms.plane_normal[i]
    return terms.plane_offset[i] - wp.dot(x_start[i], n) - wp.dot(d, n)


@wp.func
def descend_node(i: int, terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), dt: float,
                 disp: wp.array(dtype=wp.vec3)):
    """One Newton step on one node's share of the incremental potential, in the node's
    displacement d_i = x_i - x_i(t) (``disp``; see :func:`inertial_target`),

        G_i(d_i) = m_i / (2 dt^2) |d_i - y_i|^2 + E_springs + E_dampers + E_hinges,

    the other nodes held (nodes of one colour share no element or hinge, so a colour runs in
    parallel). ``spring_*`` lists each node's elements: the other node and (l0 [m], k [N/m],
    c [kg/s]). Springs contribute k (l - l0) d and the Hessian k (d d^T + max(0, 1 - l0/l)
    (I - d d^T)) (projected to be positive semi-definite); the paper's dampers
    c (v_k - v_i) with v = (x - x(t)) / dt contribute c / dt I. The hinges' energy is the
    quadratic form x^T L x / 2 with the constant matrix L = sum_h stiffness_h K_h K_h^T
    (``bend_*``: row i of L, its diagonal included; its rows sum to zero), so they add
    (L x)_i = sum_j L_ij (x_j - x_i) to the gradient and L_ii I to the Hessian. Membrane
    triangles add their St. Venant-Kirchhoff terms (:func:`membrane_gradient`). Bending
    hysteresis's elements (``slider_*``: each node's stencils with a slider, entries stencil * 4
    + the node's corner) add K_i times their returned moment
    (:func:`~party.solvers.hysteresis.slider_moment`, with c_slip at the step's start in
    ``slip_world``) and friction K_i^2 I, a bound on their Hessian.

    A node that the last Collision() found against the body steps to the minimum of its
    quadratic model on the outer side of that face's plane (``plane_*``, :func:`body_planes`):
    the Newton step, moved along H^-1 n until n . x reaches the plane where it ended behind it
    (:func:`plane_reactions` gives the plane's reaction after the sweeps).
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


@wp.kernel
def onto_planes(terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), disp: wp.array(dtype=wp.vec3)):
    """After the sweeps (the Chebyshev blend may have moved a node behind its body plane):
    each node behind its plane moved along n onto it."""
    i = wp.tid()
    n = terms.plane_normal[i]
    if terms.inv_mass[i] == 0.0 or wp.length_sq(n) == 0.0:
        return
    gap = behind_plane(terms, x_start, i, disp[i])
    if gap > 0.0:
        disp[i] = disp[i] + gap * n


@wp.kernel
def plane_reactions(terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), dt: float,
                    disp: wp.array(dtype=wp.vec3)):
    """The reaction of each node's body plane at the solve's end, lambda = n . grad G_i [N]
    where the node lies on the plane (within :data:`PLANE_CONTACT`) and grad G_i presses it into the plane (a
    node held by the plane at the minimum has grad G_i = lambda n; over a uniformly pressed
    patch the lambdas sum to its weight's normal part, the internal forces cancelling), as
    the velocity lambda dt / m along n that it gave the node, into ``plane_push``, for the
    body response's friction (:func:`~party.collision.body.collide_body`)."""
    i = wp.tid()
    n = terms.plane_normal[i]
    if terms.inv_mass[i] == 0.0 or wp.length_sq(n) == 0.0:
        return
    gap = behind_plane(terms, x_start, i, disp[i])
    if gap < -PLANE_CONTACT:
        return
    reaction = wp.max(wp.dot(n, node_terms(i, terms, x_start, dt, disp).grad), 0.0)
    terms.plane_push[i] = (reaction * dt / terms.mass[i]) * n


@wp.kernel
def block_descent(first: int, colored: wp.array(dtype=int), terms: DescentTerms, x_start: wp.array(dtype=wp.vec3),
                  dt: float, disp: wp.array(dtype=wp.vec3)):
    """:func:`descend_node` for the nodes ``colored[first + tid]`` (one colour)."""
    descend_node(colored[first + wp.tid()], terms, x_start, dt, disp)


@wp.kernel
def sweep_workers(worker: int, workers: int, sync: WorkerSync, iterations: int,
                  color_offsets: wp.array(dtype=int), omegas: wp.array(dtype=float), colored: wp.array(dtype=int),
                  terms: DescentTerms, x_start: wp.array(dtype=wp.vec3), dt: float, disp: wp.array(dtype=wp.vec3),
                  disp_previous: wp.array(dtype=wp.vec3), disp_before: wp.array(dtype=wp.vec3)):
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


@wp.kernel
def step_velocity(x_start: wp.array(dtype=wp.vec3), disp: wp.array(dtype=wp.vec3), dt: float,
                  x_out: wp.array(dtype=wp.vec3), v_out: wp.array(dtype=wp.vec3)):
    """v* = d / dt, d the solve's displacement, and x_out = x(t) for the collision pass and eq. (4)."""
    i = wp.tid()
    x_out[i] = x_start[i]
    v_out[i] = disp[i] / dt


@wp.kernel
def chebyshev_blend(x: wp.array(dtype=wp.vec3), previous: wp.array(dtype=wp.vec3), before: wp.array(dtype=wp.vec3),
                    omega: float, plane_normal: wp.array(dtype=wp.vec3)):
    """Chebyshev semi-iterative acceleration of the sweeps (Wang 2015; used by VBD):
    :func:`blend_node` for every node."""
    blend_node(wp.tid(), x, previous, before, omega, plane_normal)


@wp.func
def blend_node(i: int, x: wp.array(dtype=wp.vec3), previous: wp.array(dtype=wp.vec3),
               before: wp.array(dtype=wp.vec3), omega: float, plane_normal: wp.array(dtype=wp.vec3)):
    """x_k <- omega (x_k - x_{k-2}) + x_{k-2}; then shift the history (``previous`` = x_{k-1}
    becomes x_{k-2} in ``before``, and x_k becomes ``previous``). Along the normal of a node's
    body plane (:func:`body_planes`) x_k is kept as the sweep left it: extrapolated, a node
    that a sweep brought onto the plane from behind it would leave the plane outwards, lose
    its contact and its friction, and fall back in the next step."""
    xk = omega * (x[i] - before[i]) + before[i]
    n = plane_normal[i]
    xk += wp.dot(x[i] - xk, n) * n
    x[i] = xk
    before[i] = previous[i]
    previous[i] = xk
