"""Cloth against cloth (section 6.3): node-versus-triangle detection with the interval lists,
and the gamma/kappa momentum exchange of eqs. (13)-(14), distributed to the triangle's nodes by
barycentric weights."""

import warp as wp

from .geometry import (boxes_overlap, closest_point_barycentric, interpolate, step_box, step_near, triangle_step,
                       unchanged)
from .intervals import IntervalLists, found_once, query_axis
from .nearest import keep_nearest

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

MAX_CONTACTS = 4
"""Cloth-cloth contacts kept per node (the nearest ones)."""


@wp.func
def is_excluded(i: int, n: int, offsets: wp.array(dtype=int), excluded: wp.array(dtype=int)) -> bool:
    """Whether node n is node i or one of the nodes whose triangles node i does not collide
    with (:meth:`party.collision.pipeline.CollisionPipeline._excluded_nodes`)."""
    if i == n:
        return True
    for j in range(offsets[i], offsets[i + 1]):
        if excluded[j] == n:
            return True
    return False


MAX_CANDIDATES = 48
"""Cloth triangles remembered per node between interval-list queries."""


@wp.func
def search_reach(eps: float, margin: float, vi: wp.vec3, dt: float) -> float:
    """How far [m] from a node a triangle may lie and still be kept (:func:`keep_candidate`):
    eps, the search margin (twice ``margin``, the half margin each side may move) and the
    node's step, before adding the triangle's own step."""
    return eps + 2.0 * margin + wp.length(vi) * dt


@wp.func
def keep_candidate(i: int, t: int, x0: wp.vec3, x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3),
                   dt: float, reach: float, tris: wp.array(dtype=int, ndim=2),
                   excluded_offsets: wp.array(dtype=int), excluded: wp.array(dtype=int), count: int,
                   out: wp.array(dtype=int, ndim=2), out_distance: wp.array(dtype=float, ndim=2),
                   overflow: wp.array(dtype=int)) -> int:
    """Keep triangle t as a candidate of node i unless it holds the node or one of its excluded
    nodes, or lies farther than ``reach`` (:func:`search_reach`) plus its nodes' longest step:
    until the next search, node and triangle each move at most half the margin beyond that, so
    they cannot come within eps. Beyond MAX_CANDIDATES the farthest is replaced. Returns the
    new count."""
    ta = tris[t, 0]
    tb = tris[t, 1]
    tc = tris[t, 2]
    if (is_excluded(i, ta, excluded_offsets, excluded) or is_excluded(i, tb, excluded_offsets, excluded)
            or is_excluded(i, tc, excluded_offsets, excluded)):
        return count
    w = closest_point_barycentric(x0, x[ta], x[tb], x[tc])
    dist = wp.length(x0 - interpolate(w, x[ta], x[tb], x[tc]))
    if dist > reach + triangle_step(ta, tb, tc, v, dt):
        return count
    return keep_nearest(i, t, dist, count, MAX_CANDIDATES, out, out_distance, overflow)


@wp.kernel
def sum_motion(x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), x_ref: wp.array(dtype=wp.vec3),
               total: wp.array(dtype=wp.vec3)):
    """Sum the nodes' displacements since the search, x - x_ref [m], into ``total[0]`` and
    their velocities [m/s] into ``total[1]`` (a plain launch: one thread on the CPU)."""
    i = wp.tid()
    wp.atomic_add(total, 0, x[i] - x_ref[i])
    wp.atomic_add(total, 1, v[i])


@wp.kernel
def searched_velocity(x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), proposed: wp.array(dtype=wp.vec3),
                      dt: float, margin: float, out: wp.array(dtype=wp.vec3)):
    """The velocity [m/s] whose step a search in a Collision() after the plastic limit looks
    along at node i: the step's ``proposed`` velocity (as the first Collision() of the step had
    it) where the node's step now, from x by v dt, lies within ``margin`` [m] of the proposed
    step's segment from x, else v. The searched steps then cover the present ones, and also what
    the next step's solve proposes again for cloth that the plastic limit holds where it is:
    searched along the held steps only, a garment whose limit takes back millimetres that each
    solve proposes would have its next step's first Collision() find them beyond both keep tests
    (:func:`moved_beyond`) and search again, at every step."""
    i = wp.tid()
    start = x[i]
    if step_near(start, start + v[i] * dt, start, proposed[i] * dt, margin):
        out[i] = proposed[i]
    else:
        out[i] = v[i]


@wp.kernel
def moved_beyond(x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), x_ref: wp.array(dtype=wp.vec3),
                 step_ref: wp.array(dtype=wp.vec3), total: wp.array(dtype=wp.vec3),
                 velocity_sum_ref: wp.array(dtype=wp.vec3), share: float, dt: float, margin: float,
                 flags: wp.array(dtype=int)):
    """Flag where some node may have left the region its remembered candidates were searched
    for, by two tests; the candidates still serve while every node passes one of them (each
    takes the motion common to all nodes out differently, so a node that passes one and its
    triangle's node that passes the other prove nothing together). A common motion brings no
    node nearer a triangle, and the contacts are judged on relative steps
    (:func:`detect_cloth`), so a node and a triangle whose nodes all keep within half the
    ``margin`` [m] of where the search had them, beyond a common motion, come no nearer than
    :func:`keep_candidate` allowed for.

    ``flags[0]``: some node's displacement since the search plus its step, each beyond the
    mean of all nodes' (``share`` times ``total``, :func:`sum_motion`), passes half the margin.
    ``flags[1]``: some node's step, less the common motion since the search (the mean
    displacement, and the mean velocity's change since, ``velocity_sum_ref`` being the
    velocities' sum at the search), leaves half the margin of the step it was searched for
    (from ``x_ref`` by ``step_ref``, :func:`~party.collision.geometry.step_near`). The second
    keeps the candidates of cloth that the plastic limit holds where it is while every step's
    solve proposes the same millimetres of stretch (the shoulders and waist of a garment sewn
    tighter than its body), which would otherwise have the cloth searched at every step."""
    i = wp.tid()
    shift = share * total[0]
    moved = x[i] - x_ref[i] - shift
    if wp.length(moved) + wp.length(v[i] - share * total[1]) * dt > 0.5 * margin:
        flags[0] = 1
    start = x[i] - shift
    end = start + (v[i] - share * (total[1] - velocity_sum_ref[0])) * dt
    if not step_near(start, end, x_ref[i], step_ref[i], 0.5 * margin):
        flags[1] = 1


def _gather_cloth_triangles(bvh: bool):
    """The cloth search over the interval lists (``bvh`` False) or a BVH over the same boxes
    (:mod:`party.collision.bvh`): one kernel, whose walk over the box's candidates is the only
    part that differs."""
    structure_type = wp.uint64 if bvh else IntervalLists

    def gather_cloth_triangles(first: int, x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3),
                               thickness: wp.array(dtype=float), tris: wp.array(dtype=int, ndim=2),
                               excluded_offsets: wp.array(dtype=int), excluded: wp.array(dtype=int),
                               structure: structure_type, dt: float, margin: float, out: wp.array(dtype=int, ndim=2),
                               out_count: wp.array(dtype=int), out_distance: wp.array(dtype=float, ndim=2),
                               step_ref: wp.array(dtype=wp.vec3), overflow: wp.array(dtype=int)):
        """The search of section 6.1 against the cloth's own triangles: the box spanned by r and
        r + dr grown by eps and a margin, walked on the interval lists' axis with the fewest
        entries (or queried in a BVH of the same boxes: the same triangles). Triangles holding
        the node or one of its excluded nodes (section 6.3; see
        :meth:`~party.collision.pipeline.CollisionPipeline._excluded_nodes`) are left out; the
        nearest MAX_CANDIDATES others are kept for the following steps (the count of farther
        ones dropped goes to ``overflow``), and the node's step in ``step_ref``
        (:func:`moved_beyond`)."""
        i = first + wp.tid()
        x0 = x[i]
        step_ref[i] = v[i] * dt
        lo, hi = step_box(x0, v[i] * dt, thickness[i] + margin)
        reach = search_reach(thickness[i], margin, v[i], dt)
        count = int(0)
        if wp.static(bvh):
            query = wp.bvh_query_aabb(structure, lo, hi)
            t = int(0)
            while wp.bvh_query_next(query, t):
                count = keep_candidate(i, t, x0, x, v, dt, reach, tris, excluded_offsets, excluded, count, out,
                                       out_distance, overflow)
        else:
            sel = query_axis(structure, lo, hi)
            axis = sel[0]
            base = axis * (structure.max_cells + 1)
            for c in range(sel[1], sel[2] + 1):
                for j in range(structure.offsets[base + c], structure.offsets[base + c + 1]):
                    t = structure.ids[j]
                    if found_once(structure, t, lo, hi, axis, sel[1], c):
                        count = keep_candidate(i, t, x0, x, v, dt, reach, tris, excluded_offsets, excluded, count,
                                               out, out_distance, overflow)
        out_count[i] = count

    return wp.kernel(gather_cloth_triangles, name=f"gather_cloth_triangles_{'bvh' if bvh else 'lists'}")


gather_cloth_triangles = _gather_cloth_triangles(False)
gather_cloth_triangles_bvh = _gather_cloth_triangles(True)


@wp.func
def steps_meet(x0: wp.vec3, vi: wp.vec3, eps: float, a: wp.vec3, b: wp.vec3, c: wp.vec3, va: wp.vec3, vb: wp.vec3,
               vc: wp.vec3, dt: float) -> bool:
    """Whether the box a node sweeps from ``x0`` at ``vi`` over ``dt`` [s], grown by ``eps``
    [m], meets the box that triangle (a, b, c) sweeps at (va, vb, vc): every search, whatever its
    margin, lists such a triangle (the search grows both boxes by more), and no node comes
    within eps of a triangle whose box its own does not meet."""
    lo, hi = step_box(x0, vi * dt, eps)
    a1 = a + va * dt
    b1 = b + vb * dt
    c1 = c + vc * dt
    t_lo = wp.min(wp.min(wp.min(a, b), c), wp.min(wp.min(a1, b1), c1))
    t_hi = wp.max(wp.max(wp.max(a, b), c), wp.max(wp.max(a1, b1), c1))
    return boxes_overlap(lo, hi, t_lo, t_hi)


@wp.func
def nearer(d: float, t: int, other_d: float, other_t: int) -> bool:
    """Whether a contact at distance ``d`` [m] with triangle ``t`` comes before one at
    ``other_d`` with ``other_t`` (:func:`detect_cloth`'s order)."""
    return d < other_d or (d == other_d and t < other_t)


@wp.kernel
def detect_cloth(
    first: int,
    x: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    thickness: wp.array(dtype=float),
    tris: wp.array(dtype=int, ndim=2),
    candidates: wp.array(dtype=int, ndim=2),
    candidate_count: wp.array(dtype=int),
    dt: float,
    contact_tri: wp.array(dtype=int, ndim=2),
    contact_w: wp.array(dtype=wp.vec3, ndim=2),
    contact_n: wp.array(dtype=wp.vec3, ndim=2),
    contact_d: wp.array(dtype=float, ndim=2),
    contact_count: wp.array(dtype=int),
):
    """Find the cloth triangles a node comes within eps of during this step.

    For each candidate the closest point q (barycentric w) gives the distance d and the side n
    the node is on at the start of the step; the pair is a contact when the predicted gap
    d + ((v_i - v_q) . n) dt is below eps, and the node's step comes within eps of the
    triangle's in the boxes they sweep (:func:`steps_meet`: the prediction alone also took
    triangles that a node passes sideways, beyond their edges, at speed, and which only a search
    with a wider margin than needed had listed). The nearest MAX_CONTACTS are kept, in order of
    distance and then of triangle index: the contacts, and so the response's sums, do not depend
    on the order in which the search listed the candidates, nor on how many farther ones it
    listed (a search margin changes how often the cloth is searched, not where it goes).
    """
    i = first + wp.tid()
    x0 = x[i]
    vi = v[i]
    eps = thickness[i]
    count = int(0)
    for j in range(candidate_count[i]):
        t = candidates[i, j]
        ta = tris[t, 0]
        tb = tris[t, 1]
        tc = tris[t, 2]
        a = x[ta]
        b = x[tb]
        cc = x[tc]
        if not steps_meet(x0, vi, eps, a, b, cc, v[ta], v[tb], v[tc], dt):
            continue
        w = closest_point_barycentric(x0, a, b, cc)
        gap = x0 - interpolate(w, a, b, cc)
        d = wp.length(gap)
        nf = wp.cross(b - a, cc - a)
        nf_len = wp.length(nf)
        if nf_len < 1.0e-20:
            continue
        nf = nf / nf_len
        n = nf
        if d > 1.0e-7:
            n = gap / d
        elif wp.dot(vi, nf) > 0.0:
            n = -nf
        vq = interpolate(w, v[ta], v[tb], v[tc])
        predicted = d + wp.dot(vi - vq, n) * dt
        if predicted >= eps and d >= eps:
            continue
        # insert in (d, t) order; beyond MAX_CONTACTS the last falls off
        slot = count
        while slot > 0:
            if not nearer(d, t, contact_d[i, slot - 1], contact_tri[i, slot - 1]):
                break
            if slot < MAX_CONTACTS:
                contact_tri[i, slot] = contact_tri[i, slot - 1]
                contact_w[i, slot] = contact_w[i, slot - 1]
                contact_n[i, slot] = contact_n[i, slot - 1]
                contact_d[i, slot] = contact_d[i, slot - 1]
            slot -= 1
        if slot < MAX_CONTACTS:
            contact_tri[i, slot] = t
            contact_w[i, slot] = w
            contact_n[i, slot] = n
            contact_d[i, slot] = d
        if count < MAX_CONTACTS:
            count += 1
    contact_count[i] = count


@wp.func
def exchange(v0: wp.vec3, v1: wp.vec3, gamma: float, kappa: float) -> wp.vec3:
    """Eq. (13) in the rest frame of the struck point: v0' - v1 = kappa gamma (v0 - v1)."""
    return v1 + kappa * gamma * (v0 - v1)


@wp.kernel
def respond_cloth(
    x: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    thickness: wp.array(dtype=float),
    gamma: wp.array(dtype=float),
    kappa: wp.array(dtype=float),
    tris: wp.array(dtype=int, ndim=2),
    contact_tri: wp.array(dtype=int, ndim=2),
    contact_w: wp.array(dtype=wp.vec3, ndim=2),
    contact_n: wp.array(dtype=wp.vec3, ndim=2),
    contact_count: wp.array(dtype=int),
    dt: float,
    settled: wp.array(dtype=int),
    touched: wp.array(dtype=int),
    dv: wp.array(dtype=wp.vec3),
    dx: wp.array(dtype=wp.vec3),
    hits: wp.array(dtype=int),
):
    """Eqs. (13)-(14) for every contact of node i still closing, accumulated Jacobi-style.

    Node 0 is the colliding node, node 1 the point w of the struck triangle. In the rest frame
    of node 1 (the paper's setting, node 1 at rest): v0' = kappa gamma v0 and
    v1' = kappa (1 - gamma) v0, i.e. v1' = v1 + kappa (1 - gamma)(v0 - v1). A change of node 1's
    velocity is spread over the triangle's nodes as w_j / sum(w^2), which gives node 1 exactly
    that change. If the pair would still close the gap after the exchange (gamma > 1/2), the
    remaining normal approach is removed, split by inverse mass; a gap already under eps is
    reopened by a position correction. The gap is measured anew each pass along the normal
    found at detection (the side the node was on at the start of the step). A contact whose
    nodes the last pass left ``settled`` and this one has not ``touched`` is skipped (see
    :meth:`~party.collision.pipeline.CollisionPipeline.apply`).
    """
    i = wp.tid()
    eps = thickness[i]
    im0 = inv_mass[i]
    node_unchanged = unchanged(i, settled, touched)
    for s in range(contact_count[i]):
        t = contact_tri[i, s]
        w = contact_w[i, s]
        n = contact_n[i, s]
        ta = tris[t, 0]
        tb = tris[t, 1]
        tc = tris[t, 2]
        if (node_unchanged and unchanged(ta, settled, touched) and unchanged(tb, settled, touched)
                and unchanged(tc, settled, touched)):
            continue
        d = wp.dot(x[i] - interpolate(w, x[ta], x[tb], x[tc]), n)
        v0 = v[i]
        v1 = interpolate(w, v[ta], v[tb], v[tc])
        un = wp.dot(v0 - v1, n)
        closing = d + un * dt < eps
        if not closing and d >= eps:
            continue
        im1 = w[0] * w[0] * inv_mass[ta] + w[1] * w[1] * inv_mass[tb] + w[2] * w[2] * inv_mass[tc]
        if im0 + im1 == 0.0:
            continue
        w2 = wp.dot(w, w)
        d0 = wp.vec3(0.0)
        d1 = wp.vec3(0.0)
        if closing and un < 0.0:
            if im0 > 0.0 and im1 > 0.0:
                v0n = exchange(v0, v1, gamma[i], kappa[i])
                v1n = v1 + kappa[i] * (1.0 - gamma[i]) * (v0 - v1)
                d0 = v0n - v0
                d1 = v1n - v1
            rest = wp.dot((v0 + d0) - (v1 + d1), n)
            if rest < 0.0:
                lam = -rest / (im0 + im1)
                d0 = d0 + lam * im0 * n
                d1 = d1 - lam * im1 * n
        p0 = wp.vec3(0.0)
        p1 = wp.vec3(0.0)
        if d < eps:
            depth = eps - d
            p0 = depth * im0 / (im0 + im1) * n
            p1 = -depth * im1 / (im0 + im1) * n
        if im0 > 0.0:
            wp.atomic_add(dv, i, d0)
            wp.atomic_add(dx, i, p0)
            wp.atomic_add(hits, i, 1)
        for k in range(3):
            node = tris[t, k]
            if inv_mass[node] > 0.0 and w[k] > 0.0:
                share = w[k] / w2
                wp.atomic_add(dv, node, share * d1)
                wp.atomic_add(dx, node, share * p1)
                wp.atomic_add(hits, node, 1)


@wp.kernel
def apply_cloth_response(
    x: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    dv: wp.array(dtype=wp.vec3),
    dx: wp.array(dtype=wp.vec3),
    hits: wp.array(dtype=int),
    touched: wp.array(dtype=int),
):
    """Average each node's accumulated corrections over its contacts, apply, and reset;
    mark the nodes that had any as ``touched`` (even where a correction too small to change
    a float was all they had: it still counts in the average)."""
    i = wp.tid()
    h = hits[i]
    if h > 0:
        scale = 1.0 / float(h)
        v[i] = v[i] + dv[i] * scale
        x[i] = x[i] + dx[i] * scale
        touched[i] = 1
        dv[i] = wp.vec3(0.0)
        dx[i] = wp.vec3(0.0)
        hits[i] = 0
