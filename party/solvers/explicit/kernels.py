"""Kernels of the explicit solver (paper sections 4-5)."""

import warp as wp

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels


@wp.kernel
def net_forces_and_velocity(
    x: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    elem_offsets: wp.array(dtype=int),
    elem_ids: wp.array(dtype=int),
    elem_nodes: wp.array(dtype=wp.vec2i),
    rest_length: wp.array(dtype=float),
    stiffness: wp.array(dtype=float),
    damping: wp.array(dtype=float),
    f_ext: wp.array(dtype=wp.vec3),
    gravity: wp.vec3,
    kinematic_velocity: wp.array(dtype=wp.vec3),
    dt: float,
    x_out: wp.array(dtype=wp.vec3),
    v_out: wp.array(dtype=wp.vec3),
):
    """Eq. (3) with f_int = f_spring + f_visco (section 5), gathered per node:

    f_spring = sum_k e_ik l_ik d_ik,  l_ik = |r_k - r_i| - l0_ik,  d_ik = (r_k - r_i)/|r_k - r_i|
    f_visco  = sum_k c_ik (v_k - v_i)
    v* = v + (df / m + G) dt

    Kinematic nodes take the velocity the control imposes. Positions are copied to x_out for the
    collision pass and eq. (4).
    """
    i = wp.tid()
    xi = x[i]
    x_out[i] = xi
    if inv_mass[i] == 0.0:
        v_out[i] = kinematic_velocity[i]
        return
    vi = v[i]
    f = f_ext[i]
    for j in range(elem_offsets[i], elem_offsets[i + 1]):
        e = elem_ids[j]
        pair = elem_nodes[e]
        k = pair[0]
        if k == i:
            k = pair[1]
        d = x[k] - xi
        length = wp.length(d)
        if length > 1.0e-12:
            f += stiffness[e] * (length - rest_length[e]) * (d / length)
        f += damping[e] * (v[k] - vi)
    v_out[i] = vi + (f * inv_mass[i] + gravity) * dt


@wp.kernel
def kinetic_damping(v_before: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), max_speed: float, keep: float):
    """Relaxation's velocity filter (see :mod:`party.solvers.relax`): zero a node's velocity
    where the step turned it against the velocity it had, cap speeds at ``max_speed`` [m/s],
    and keep a fraction ``keep`` of the rest."""
    i = wp.tid()
    vi = v[i]
    if wp.dot(vi, v_before[i]) < 0.0:
        v[i] = wp.vec3(0.0)
        return
    speed = wp.length(vi)
    if speed > max_speed:
        vi = vi * (max_speed / speed)
    v[i] = vi * keep


@wp.kernel
def cap_speed(v: wp.array(dtype=wp.vec3), max_speed: float):
    """Scale every velocity down to at most ``max_speed`` [m/s]."""
    i = wp.tid()
    speed = wp.length(v[i])
    if speed > max_speed:
        v[i] = v[i] * (max_speed / speed)


@wp.func
def end_of_step_span(x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), i: int, k: int, dt: float) -> wp.vec3:
    """(r_k + v_k dt) - (r_i + v_i dt): the element's vector at the end of the step [m]."""
    return (x[k] + v[k] * dt) - (x[i] + v[i] * dt)


@wp.struct
class LimitArrays:
    """What every sweep of the plastic limit reads: the elements in colour order (``colored``,
    element ids), their nodes and longest lengths (1 + L_sh) l0 [m], the nodes' inverse masses
    [1/kg], the relative ``tolerance`` beyond the limit that counts, and ``skip_unchanged``
    (see :func:`limit_element`)."""

    colored: wp.array(dtype=int)
    elem_nodes: wp.array(dtype=wp.vec2i)
    max_length: wp.array(dtype=float)
    inv_mass: wp.array(dtype=float)
    tolerance: float
    skip_unchanged: int


@wp.func
def limit_element(limit: LimitArrays, e: int, x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), dt: float,
                  over_relaxation: float, sweep: int, moved_in: wp.array(dtype=int)) -> int:
    """f_plas (section 5, figure 5) on element e: an element may not stretch beyond
    (1 + L_sh) l0.

    For an element whose length at the end of the step, |(r_k + v_k dt) - (r_i + v_i dt)|,
    would pass the limit, the relative velocity that stretches it further is cancelled (split
    by inverse mass), which is the force component f_plas removes; ``over_relaxation`` > 1
    cancels that much more (projected successive over-relaxation, see
    :class:`~party.solvers.plastic_limit.PlasticLimit`). Returns 1 where the element was beyond (1 +
    ``tolerance``) times its limit.

    Each node a correction changes is marked in ``moved_in`` with the number of the sweep
    (from 1). With ``skip_unchanged`` 1, from the second sweep on, an element neither of whose
    nodes a correction has moved in the last sweep or so far in this one is left out: it is as
    it was when the last sweep found it within its limit.
    """
    pair = limit.elem_nodes[e]
    i = pair[0]
    k = pair[1]
    if limit.skip_unchanged == 1 and sweep > 1 and wp.max(moved_in[i], moved_in[k]) < sweep - 1:
        return 0
    wi = limit.inv_mass[i]
    wk = limit.inv_mass[k]
    if wi + wk == 0.0:
        return 0
    p = end_of_step_span(x, v, i, k, dt)
    length = wp.length(p)
    longest = limit.max_length[e]
    if length <= longest:
        return 0
    beyond = int(0)
    if length > longest * (1.0 + limit.tolerance):
        beyond = 1
    direction = p / length
    excess = over_relaxation * (length - longest) / (dt * (wi + wk))
    v[i] = v[i] + direction * (excess * wi)
    v[k] = v[k] - direction * (excess * wk)
    if wi > 0.0:
        moved_in[i] = sweep
    if wk > 0.0:
        moved_in[k] = sweep
    return beyond


@wp.kernel
def plastic_limit(limit: LimitArrays, offset: int, x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3),
                  dt: float, over_relaxation: float, sweep_number: wp.array(dtype=int), moved_in: wp.array(dtype=int),
                  over: wp.array(dtype=int)):
    """One colour's share of a sweep of the plastic limit (:func:`limit_element`), in the sweep
    ``sweep_number[0]``. Elements of one colour share no node, so a colour is processed in
    parallel; colours run one after another. ``over`` counts the elements found beyond (1 +
    ``tolerance``) times their limit."""
    if limit_element(limit, limit.colored[offset + wp.tid()], x, v, dt, over_relaxation, sweep_number[0],
                     moved_in) != 0:
        wp.atomic_add(over, 0, 1)


@wp.kernel
def plastic_limit_sweeps(limit: LimitArrays, x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), dt: float,
                         over_relaxation: float, max_sweeps: int, moved_in: wp.array(dtype=int),
                         sweeps: wp.array(dtype=int)):
    """Every sweep of the plastic limit in one thread (the CPU's serial launch): sweeps over
    all elements in colour order until one finds none beyond (1 + ``tolerance``) times its
    limit, at most ``max_sweeps``; the number taken goes to ``sweeps[0]``. The same sweeps as
    :func:`plastic_limit` over the colours, with no launch or read of the count between them."""
    sweep = int(0)
    while sweep < max_sweeps:
        sweep += 1
        beyond = int(0)
        for j in range(limit.colored.shape[0]):
            beyond += limit_element(limit, limit.colored[j], x, v, dt, over_relaxation, sweep, moved_in)
        if beyond == 0:
            break
    sweeps[0] = sweep


@wp.kernel
def next_sweep(sweep_number: wp.array(dtype=int), over: wp.array(dtype=int)):
    """Start a sweep of the plastic limit: count it and clear the count of elements found
    beyond."""
    sweep_number[0] = sweep_number[0] + 1
    over[0] = 0


@wp.kernel
def advance_positions(x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), dt: float):
    """Eq. (4): r(t + dt) = r(t) + v(t + dt) dt."""
    i = wp.tid()
    x[i] = x[i] + v[i] * dt


@wp.func
def stencil_curvature(x: wp.array(dtype=wp.vec3), n: wp.vec4i, w: wp.vec4) -> wp.vec3:
    """A bending stencil's curvature vector k = sum_i K_i x_i (:mod:`party.meshing.hinges`)."""
    return w[0] * x[n[0]] + w[1] * x[n[1]] + w[2] * x[n[2]] + w[3] * x[n[3]]


@wp.kernel
def hinge_forces(
    x: wp.array(dtype=wp.vec3),
    hinge_nodes: wp.array(dtype=wp.vec4i),
    hinge_weights: wp.array(dtype=wp.vec4),
    hinge_stiffness: wp.array(dtype=float),
    f: wp.array(dtype=wp.vec3),
):
    """Bending (:mod:`party.meshing.hinges`): with k = sum_i K_i x_i, each corner i of a hinge
    takes f_i = -stiffness K_i k [N], added to ``f``."""
    h = wp.tid()
    n = hinge_nodes[h]
    w = hinge_weights[h]
    k = stencil_curvature(x, n, w)
    s = hinge_stiffness[h]
    for c in range(4):
        wp.atomic_add(f, n[c], -s * w[c] * k)
