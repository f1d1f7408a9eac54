"""Cloth against body: detection along the step (section 6.1, condition (6)) and the
response of eqs. (8)-(12)."""

import warp as wp

from .geometry import (PUSH_SPENT, closest_point_barycentric, differs, friction_restitution_response,
                       interpolate, step_box, step_within, unchanged)
from .intervals import IntervalLists, found_once, query_axis

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

EDGE_TOLERANCE = 0.25
"""A node whose projection falls outside a triangle by up to this fraction of the thickness
still counts as over it, so that no node slips between two adjacent triangles."""

MAX_FACES = 24
"""Body triangles remembered per node between interval-list queries."""


@wp.func
def face_normal(f: int, faces: wp.array(dtype=int, ndim=2), body_q: wp.array(dtype=wp.vec3)) -> wp.vec3:
    """The unit normal of body face ``f`` (its corners' winding), at the positions ``body_q``."""
    a = body_q[faces[f, 0]]
    return wp.normalize(wp.cross(body_q[faces[f, 1]] - a, body_q[faces[f, 2]] - a))


@wp.func
def still_covered(x: wp.vec3, v: wp.vec3, ref: wp.vec3, dt: float, margin: float) -> bool:
    """Whether a node at ``x`` stepping ``v dt`` stays within ``margin`` [m] of ``ref``, the
    place its candidates were searched from (``margin`` is half the search margin)."""
    return wp.length(x - ref) + wp.length(v) * dt <= margin


@wp.func
def covered(x: wp.vec3, v: wp.vec3, dt: float, ref: wp.vec3, ref_step: wp.vec3, margin: float,
            continuing: int, complete: bool) -> bool:
    """Whether a node's candidates still serve its step from ``x`` by ``v dt``: it stays within
    ``margin`` (half the search margin) of where it was searched from (:func:`still_covered`),
    or of the box of the step it was searched for (:func:`step_within`). The box counts in a
    second Collision() of the same step (``continuing`` 1), and between steps only where the
    search kept all it found (``complete``): a full list holds what was nearest then (the 8
    nearest body vertices of a cloth triangle), and another vertex may be nearer since. The
    box's corners reach sqrt(3) times the margin from the searched step, within the two margins
    the search allowed for, as only the cloth moves (a pair of cloth nodes and triangles needs
    :func:`~party.collision.geometry.step_near`)."""
    if still_covered(x, v, ref, dt, margin):
        return True
    return (continuing != 0 or complete) and step_within(x, x + v * dt, ref, ref_step, margin)


@wp.func
def keep_face(i: int, f: int, count: int, faces_out: wp.array(dtype=int, ndim=2), overflow: wp.array(dtype=int)) -> int:
    """Keep body face ``f`` as node ``i``'s ``count``-th candidate where there is room (else
    count it in ``overflow``); the count after."""
    if count < MAX_FACES:
        faces_out[i, count] = f
        return count + 1
    wp.atomic_add(overflow, 0, 1)
    return count


def _gather_body_faces(bvh: bool):
    """The body-face search over the interval lists (``bvh`` False) or a BVH over the same boxes
    (:mod:`party.collision.bvh`): one kernel, whose walk over the box's candidates is the only
    part that differs."""
    structure_type = wp.uint64 if bvh else IntervalLists

    def gather_body_faces(first: int, x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3),
                          inv_mass: wp.array(dtype=float), thickness: wp.array(dtype=float), structure: structure_type,
                          dt: float, margin: float, everything: int, continuing: int, ref: wp.array(dtype=wp.vec3),
                          ref_step: wp.array(dtype=wp.vec3), searched_again: wp.array(dtype=int),
                          ignored_parts: wp.array(dtype=int), face_parts: wp.array(dtype=int),
                          faces_out: wp.array(dtype=int, ndim=2), face_count: wp.array(dtype=int),
                          overflow: wp.array(dtype=int)):
        """Section 6.1's search: the box spanned by r and r + dr, grown by eps and a margin that
        lets the answer serve the next steps, walked on the interval lists' axis with the
        fewest entries and box-checked in 3-D (or queried in a BVH of the same boxes: the same
        triangles). The triangles found are kept for the narrow phase, and r in ``ref`` and the
        step in ``ref_step``. With ``everything`` 0 only nodes whose step left the region
        searched (:func:`covered`) search again (the body must be static then, or
        ``continuing``); with ``continuing`` 1 they are marked in ``searched_again``. Faces of
        the body parts a node passes through (``ignored_parts[i] & face_parts[f]``) are not
        kept."""
        i = first + wp.tid()
        if everything == 0 and covered(x[i], v[i], dt, ref[i], ref_step[i], margin, continuing,
                                       face_count[i] < MAX_FACES):
            return
        if continuing != 0:
            searched_again[i] = 1
        ref[i] = x[i]
        ref_step[i] = v[i] * dt
        face_count[i] = 0
        if inv_mass[i] == 0.0:
            return
        lo, hi = step_box(x[i], v[i] * dt, thickness[i] + margin)
        count = int(0)
        ignored = ignored_parts[i]
        if wp.static(bvh):
            query = wp.bvh_query_aabb(structure, lo, hi)
            f = int(0)
            while wp.bvh_query_next(query, f):
                if (face_parts[f] & ignored) == 0:
                    count = keep_face(i, f, count, faces_out, overflow)
        else:
            sel = query_axis(structure, lo, hi)
            axis = sel[0]
            base = axis * (structure.max_cells + 1)
            for c in range(sel[1], sel[2] + 1):
                for j in range(structure.offsets[base + c], structure.offsets[base + c + 1]):
                    f = structure.ids[j]
                    if found_once(structure, f, lo, hi, axis, sel[1], c) and (face_parts[f] & ignored) == 0:
                        count = keep_face(i, f, count, faces_out, overflow)
        face_count[i] = count

    return wp.kernel(gather_body_faces, name=f"gather_body_faces_{'bvh' if bvh else 'lists'}")


gather_body_faces = _gather_body_faces(False)
gather_body_faces_bvh = _gather_body_faces(True)


@wp.kernel
def collide_body(
    first: int,
    x: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    thickness: wp.array(dtype=float),
    friction: wp.array(dtype=float),
    restitution: wp.array(dtype=float),
    body_q: wp.array(dtype=wp.vec3),
    body_qd: wp.array(dtype=wp.vec3),
    body_normals: wp.array(dtype=wp.vec3, ndim=2),
    faces: wp.array(dtype=int, ndim=2),
    candidates: wp.array(dtype=int, ndim=2),
    candidate_count: wp.array(dtype=int),
    dt: float,
    arrive: int,
    settled: wp.array(dtype=int),
    touched: wp.array(dtype=int),
    contact_face: wp.array(dtype=int),
    solve_push: wp.array(dtype=wp.vec3),
):
    """One detection-and-response pass for each free node over its candidate triangles.

    The node moves from r to r + (v - v_body) dt relative to each triangle. It collides when
    that step brings it within the thickness eps of the triangle's plane over the triangle (or
    it already rests within eps, or has been pushed up to eps inside): condition (6). The
    earliest such contact wins; its point p gives the body normal n (interpolated corner
    normals, smooth except across creases) and the body velocity at p. Eqs. (8)-(12) give the new velocity; if the step would
    still end closer than eps to the triangle, the node's start is moved out along the face
    normal so that the step ends at eps (a position correction, adding no velocity). With
    ``arrive`` (ours, for large steps), a node that starts farther than eps from the triangle's
    plane is first moved along its normal to eps, where its step would have reached it, and
    takes the new velocity from there; as printed, the response leaves it where it started, up
    to a step's approach off the body.

    Skips a node left ``settled`` by the last pass and not ``touched`` by this one (see
    :meth:`~party.collision.pipeline.CollisionPipeline.apply`) and marks one it changes. The
    face of the contact goes to ``contact_face`` (the implicit solver's next solve keeps the
    node on its side of that face's plane). ``solve_push`` [m/s] is the velocity that plane's
    reaction gave the node in the solve (``plane_reactions`` of :mod:`party.solvers.implicit.descent`):
    the first pass finds the contact with the node's velocity without it, as the node would
    have struck the body, and the friction cone takes it as normal impulse (not the bounce); it
    is used once and cleared, and the node is not settled for the next pass, which may answer
    otherwise without it (``touched`` gets :data:`~party.collision.geometry.PUSH_SPENT`; the
    passes that skip settled nodes then stay bit for bit the same as full passes), though it
    does not count as changed.
    """
    i = first + wp.tid()
    if inv_mass[i] == 0.0 or unchanged(i, settled, touched):
        return
    x0 = x[i]
    v_given = v[i]
    push = solve_push[i]
    vi = v_given - push
    if wp.length_sq(push) > 0.0:  # the next pass answers without it: not settled, though not changed
        solve_push[i] = wp.vec3(0.0)
        touched[i] = touched[i] | PUSH_SPENT
    eps = thickness[i]
    best_t = float(2.0)
    best_s1 = float(1.0e30)
    best_face = int(-1)
    best_w = wp.vec3(0.0)
    for j in range(candidate_count[i]):
        f = candidates[i, j]
        a = body_q[faces[f, 0]]
        b = body_q[faces[f, 1]]
        cc = body_q[faces[f, 2]]
        nf = wp.normalize(wp.cross(b - a, cc - a))
        vb = (body_qd[faces[f, 0]] + body_qd[faces[f, 1]] + body_qd[faces[f, 2]]) / 3.0
        dr = (vi - vb) * dt
        s0 = wp.dot(x0 - a, nf)
        s1 = s0 + wp.dot(dr, nf)
        if s0 < -eps or s1 >= eps:
            continue
        t = float(0.0)
        if s0 > eps:
            t = (s0 - eps) / (s0 - s1)
        xt = x0 + dr * t
        w = closest_point_barycentric(xt, a, b, cc)
        offset = xt - interpolate(w, a, b, cc)
        lateral = offset - wp.dot(offset, nf) * nf
        if wp.length(lateral) > EDGE_TOLERANCE * eps:
            continue
        if t < best_t or (t == best_t and s1 < best_s1):
            best_t = t
            best_s1 = s1
            best_face = f
            best_w = w
    if best_face < 0:
        return

    contact_face[i] = best_face
    fa = faces[best_face, 0]
    fb = faces[best_face, 1]
    fc = faces[best_face, 2]
    a = body_q[fa]
    nf = face_normal(best_face, faces, body_q)
    n = wp.normalize(interpolate(best_w, body_normals[best_face, 0], body_normals[best_face, 1],
                                 body_normals[best_face, 2]))
    if wp.dot(n, nf) <= 0.0:
        n = nf
    vbody = interpolate(best_w, body_qd[fa], body_qd[fb], body_qd[fc])
    vnew = friction_restitution_response(v_given - vbody, n, friction[i], restitution[i], wp.dot(push, n)) + vbody
    s_start = wp.dot(x0 - a, nf)
    if arrive == 1 and s_start > eps:
        x0 = x0 - (s_start - eps) * nf
        s_start = eps
        x[i] = x0
        touched[i] = 1
    s_end = s_start + wp.dot(vnew - vbody, nf) * dt
    if s_end < eps:
        x[i] = x0 + (eps - s_end) * nf
        touched[i] = 1
    if differs(vnew, v_given):
        touched[i] = 1
    v[i] = vnew
