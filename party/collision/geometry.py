"""Stateless geometric primitives used by detection and response (Warp functions)."""

import warp as wp


@wp.func
def closest_point_barycentric(p: wp.vec3, a: wp.vec3, b: wp.vec3, c: wp.vec3) -> wp.vec3:
    """Barycentric weights (wa, wb, wc) of the point of triangle abc closest to p
    (Ericson, Real-Time Collision Detection, 5.1.5)."""
    ab = b - a
    ac = c - a
    ap = p - a
    d1 = wp.dot(ab, ap)
    d2 = wp.dot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return wp.vec3(1.0, 0.0, 0.0)
    bp = p - b
    d3 = wp.dot(ab, bp)
    d4 = wp.dot(ac, bp)
    if d3 >= 0.0 and d4 <= d3:
        return wp.vec3(0.0, 1.0, 0.0)
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        t = d1 / (d1 - d3)
        return wp.vec3(1.0 - t, t, 0.0)
    cp = p - c
    d5 = wp.dot(ab, cp)
    d6 = wp.dot(ac, cp)
    if d6 >= 0.0 and d5 <= d6:
        return wp.vec3(0.0, 0.0, 1.0)
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        t = d2 / (d2 - d6)
        return wp.vec3(1.0 - t, 0.0, t)
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return wp.vec3(0.0, 1.0 - t, t)
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    return wp.vec3(1.0 - v - w, v, w)


@wp.func
def interpolate(w: wp.vec3, a: wp.vec3, b: wp.vec3, c: wp.vec3) -> wp.vec3:
    return w[0] * a + w[1] * b + w[2] * c


@wp.func
def triangle_step(a: int, b: int, c: int, v: wp.array(dtype=wp.vec3), dt: float) -> float:
    """The longest step [m] of triangle (a, b, c)'s nodes at velocities ``v`` over ``dt``."""
    return wp.max(wp.length(v[a]), wp.max(wp.length(v[b]), wp.length(v[c]))) * dt


@wp.func
def step_box(x0: wp.vec3, step: wp.vec3, pad: float):
    """The box spanned by a node's step from ``x0`` to ``x0 + step``, grown by ``pad`` [m]
    (section 6.1's search box): returns (lower, upper)."""
    x1 = x0 + step
    return wp.min(x0, x1) - wp.vec3(pad), wp.max(x0, x1) + wp.vec3(pad)


@wp.func
def step_within(start: wp.vec3, end: wp.vec3, ref: wp.vec3, ref_step: wp.vec3, margin: float) -> bool:
    """Whether a step from ``start`` to ``end`` stays within ``margin`` [m] of the box spanned by
    the step its candidates were searched for, from ``ref`` by ``ref_step``: the search grew
    that box by eps and the margin, so the candidates cover any such step too."""
    lo, hi = step_box(ref, ref_step, margin)
    return (lo[0] <= wp.min(start[0], end[0]) and wp.max(start[0], end[0]) <= hi[0]
            and lo[1] <= wp.min(start[1], end[1]) and wp.max(start[1], end[1]) <= hi[1]
            and lo[2] <= wp.min(start[2], end[2]) and wp.max(start[2], end[2]) <= hi[2])


@wp.func
def step_near(start: wp.vec3, end: wp.vec3, ref: wp.vec3, ref_step: wp.vec3, margin: float) -> bool:
    """Whether a step from ``start`` to ``end`` stays within ``margin`` [m] of the segment of the
    step its candidates were searched for, from ``ref`` by ``ref_step`` (both ends do: the
    points within a distance of a segment make a convex set). Each point of such a step lies
    no farther than the searched step's length plus ``margin`` from ``ref``, the bound that
    :func:`~party.collision.cloth.keep_candidate` kept triangles by; a box grown by the margin
    (:func:`step_within`) reaches sqrt(3) times as far at its corners."""
    ref_end = ref + ref_step
    return (segment_segment_distance(start, start, ref, ref_end) <= margin
            and segment_segment_distance(end, end, ref, ref_end) <= margin)


@wp.func
def boxes_overlap(lo0: wp.vec3, hi0: wp.vec3, lo1: wp.vec3, hi1: wp.vec3) -> bool:
    return (lo0[0] <= hi1[0] and lo1[0] <= hi0[0] and lo0[1] <= hi1[1] and lo1[1] <= hi0[1]
            and lo0[2] <= hi1[2] and lo1[2] <= hi0[2])


@wp.func
def friction_restitution_response(vr: wp.vec3, n: wp.vec3, mu: float, sigma: float, pressed: float) -> wp.vec3:
    """Eqs. (8)-(11): the new relative velocity of a node striking a body.

    ``vr`` is the node's velocity relative to the body point, ``n`` the body normal there.
    Split vr into normal and tangential parts; inside the friction cone (|v_t| < mu |v_n|) the
    tangential part stops, outside it shrinks by mu |v_n|; the normal part reverses, scaled by
    the restitution sigma. Only approaching velocities (v . n < 0) change. ``pressed`` [m/s]
    adds to |v_n| in the cone (not to the bounce): the normal speed a body plane took from
    the node in the implicit solve, which held it there (0 elsewhere).
    """
    un = wp.dot(vr, n)
    press = wp.max(-un, 0.0) + pressed
    if press <= 0.0:
        return vr
    vn = un * n
    vt = vr - vn
    speed_t = wp.length(vt)
    limit = mu * press
    if speed_t <= limit:
        vt = wp.vec3(0.0)
    else:
        vt = vt * ((speed_t - limit) / speed_t)
    if un >= 0.0:
        return vt + vn
    return vt - sigma * vn


@wp.func
def segment_hits_triangle(p: wp.vec3, q: wp.vec3, a: wp.vec3, b: wp.vec3, c: wp.vec3) -> bool:
    """Strict segment-triangle intersection (Moller-Trumbore on the segment)."""
    d = q - p
    e1 = b - a
    e2 = c - a
    h = wp.cross(d, e2)
    det = wp.dot(e1, h)
    if wp.abs(det) < 1.0e-18:
        return False
    inv = 1.0 / det
    s = p - a
    u = inv * wp.dot(s, h)
    if u < 0.0 or u > 1.0:
        return False
    qv = wp.cross(s, e1)
    w = inv * wp.dot(d, qv)
    if w < 0.0 or u + w > 1.0:
        return False
    t = inv * wp.dot(e2, qv)
    return t > 0.0 and t < 1.0


@wp.func
def edge_shares_node(i: int, k: int, t: int, tris: wp.array(dtype=int, ndim=2)) -> bool:
    """Whether mesh edge (i, k) and triangle t share a node."""
    a = tris[t, 0]
    b = tris[t, 1]
    c = tris[t, 2]
    return a == i or a == k or b == i or b == k or c == i or c == k


@wp.func
def edge_pierces_triangle(i: int, k: int, t: int, points: wp.array(dtype=wp.vec3),
                          tris: wp.array(dtype=int, ndim=2)) -> bool:
    """Whether mesh edge (i, k) passes through cloth triangle t; a triangle sharing a node with
    the edge never counts."""
    if edge_shares_node(i, k, t, tris):
        return False
    return segment_hits_triangle(points[i], points[k], points[tris[t, 0]], points[tris[t, 1]], points[tris[t, 2]])


@wp.func
def segment_segment_distance(p1: wp.vec3, q1: wp.vec3, p2: wp.vec3, q2: wp.vec3) -> float:
    """Smallest distance between segments p1q1 and p2q2 (Ericson, Real-Time Collision
    Detection, 5.1.9)."""
    d1 = q1 - p1
    d2 = q2 - p2
    r = p1 - p2
    a = wp.dot(d1, d1)
    e = wp.dot(d2, d2)
    f = wp.dot(d2, r)
    s = float(0.0)
    t = float(0.0)
    if a <= 1.0e-20 and e <= 1.0e-20:
        return wp.length(r)
    if a <= 1.0e-20:
        t = wp.clamp(f / e, 0.0, 1.0)
    else:
        c = wp.dot(d1, r)
        if e <= 1.0e-20:
            s = wp.clamp(-c / a, 0.0, 1.0)
        else:
            b = wp.dot(d1, d2)
            denom = a * e - b * b
            if denom > 1.0e-20:
                s = wp.clamp((b * f - c * e) / denom, 0.0, 1.0)
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = wp.clamp(-c / a, 0.0, 1.0)
            elif t > 1.0:
                t = 1.0
                s = wp.clamp((b - c) / a, 0.0, 1.0)
    return wp.length(p1 + d1 * s - (p2 + d2 * t))


@wp.func
def segment_triangle_distance(p: wp.vec3, q: wp.vec3, a: wp.vec3, b: wp.vec3, c: wp.vec3) -> float:
    """Smallest distance between segment pq and triangle abc (zero where the segment passes
    through it)."""
    if segment_hits_triangle(p, q, a, b, c):
        return 0.0
    d = wp.min(wp.length(p - interpolate(closest_point_barycentric(p, a, b, c), a, b, c)),
               wp.length(q - interpolate(closest_point_barycentric(q, a, b, c), a, b, c)))
    d = wp.min(d, segment_segment_distance(p, q, a, b))
    d = wp.min(d, segment_segment_distance(p, q, b, c))
    return wp.min(d, segment_segment_distance(p, q, c, a))


@wp.func
def differs(a: wp.vec3, b: wp.vec3) -> bool:
    """a and b differ in any component (bitwise for finite values)."""
    return a[0] != b[0] or a[1] != b[1] or a[2] != b[2]


PUSH_SPENT = wp.constant(2)
"""Flag in ``touched`` beside 1 (changed): the node's solve push was used up in this pass
(:func:`~party.collision.body.collide_body`), so the next pass must not skip it."""


@wp.func
def unchanged(i: int, settled: wp.array(dtype=int), touched: wp.array(dtype=int)) -> bool:
    """Node i was left as it was by the last pass of Collision() (``settled``) and so far by
    this one (not ``touched``; see :meth:`~party.collision.pipeline.CollisionPipeline.apply`)."""
    return settled[i] == 1 and touched[i] == 0
