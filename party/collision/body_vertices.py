"""Body vertices against cloth triangles (ours, beyond section 6).

The paper tests each cloth node against the body's triangles, which keeps every node at eps
outside the body. Between its nodes a cloth triangle is flat, and where the body is curved
more tightly than the cloth's triangles are long (an arm under a 20 mm net) or has a sharp
feature (a rim, a shoulder's vertex), the body's own vertices come through the triangle's
interior: a garment draped with no node inside the body still shows patches of skin through
its sleeves and bodice. For a convex
patch of body the point nearest a triangle is one of its vertices, so each cloth triangle is
also tested against the body vertices near it, as a node against a body triangle: the closest
point q of the triangle to a vertex p gives the cloth point's height s = (q - p) . n_p over
the body along the vertex normal n_p (at a convex vertex on a crease, a rim or a box's edge,
along whichever of it and the faces' normals there faces the point most:
:func:`facing_normal`); where the step would end it closer than a quarter of eps
(:data:`GAP`), its approach is stopped and its start moved out along n_p, the change spread
over the triangle's nodes by their weights (as the struck point of a cloth contact is,
eqs. (13)-(14)).

Only the vertices that could come that near are tested (:func:`vertices_to_test`): over a large,
smooth body, cloth held eps off its faces cannot meet a vertex between its nodes.
"""

import numpy as np
import warp as wp

from ..body.relief import vertex_relief
from ..model import Model
from .body import EDGE_TOLERANCE, covered, face_normal
from .geometry import closest_point_barycentric, interpolate, triangle_step
from .nearest import keep_nearest

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

GAP = 0.25
"""The clearance kept between a body vertex and the cloth over it, as a fraction of eps: enough
that the body does not show through, less than the nodes' eps, so that a garment tight on
the body is not stretched further by holding its triangles' middles out as far as its
nodes: a garment sewn tighter than its body (GarmentCode's flare dress on mean_all) stretches
further with the full eps, and not with a quarter."""

RESTING = 1.01
"""A node within this many thicknesses of the plane of its contact face rests on the body (the
body response leaves such a node at eps, to round-off)."""

RELIEF_REACH = 0.1
"""Largest reach [m] over which the body's relief is worth measuring: cloth whose triangles
may stretch farther (a coarse net, a garment sewn far beyond its limit) could come near most
vertices of a body anyway, and every one is tested."""

MAX_VERTICES = 8
"""Body vertices remembered per cloth triangle between searches (the nearest ones)."""


def vertices_to_test(model: Model) -> np.ndarray:
    """The body vertices (indices into the colliders' vertices, all together) that cloth held
    eps off the body could bring within :data:`GAP` eps of a cloth triangle over them.

    The cloth point over vertex p is sum_k w_k x_k, each node x_k = f_k + eps m_k at eps off
    the body (f_k its nearest body point, m_k the unit normal there), so its height over p along
    p's normal n_p is at least eps min_k (m_k . n_p) - max_k (p - f_k) . n_p. The f_k lie within
    a reach of p: the cloth's longest triangle edge stretched to its warp and weft's plastic
    limit, plus (1 + :data:`~party.collision.body.EDGE_TOLERANCE`) eps. So p needs no test
    where eps c - r >= GAP eps, r how far p rises along n_p above the body within the reach and
    c the smallest cosine between n_p and the body's normals there
    (:func:`~party.body.relief.vertex_relief`). Taking the farthest node for all three makes the
    bound generous, so smooth bodies leave most vertices untested. Every vertex is tested
    where a body deforms (its vertices' velocities differ) or the net has no plastic limit to
    bound its triangles."""
    colliders = model.host.colliders
    total = sum(len(c.vertices) for c in colliders)
    every = np.arange(total)
    rest = model.element_rest_length.numpy()
    limit = model.element_max_length.numpy()
    limited = model.limited_elements
    velocity = np.asarray(model.collider_velocity, dtype=float).reshape(-1, 3)
    if not limited.any() or model.triangle_count == 0 or np.ptp(velocity, axis=0).max(initial=0.0) > 0.0:
        return every
    stretch = float((limit[limited] / rest[limited]).max())
    edges = np.linalg.inv(model.triangle_inv_rest.numpy().astype(np.float64))  # columns: rest edges e1, e2
    e1, e2 = edges[:, :, 0], edges[:, :, 1]
    longest = float(np.sqrt(max((e1 * e1).sum(1).max(), (e2 * e2).sum(1).max(), ((e2 - e1) ** 2).sum(1).max())))
    eps = float(model.node_thickness.numpy().max())
    reach = longest * stretch + (1.0 + EDGE_TOLERANCE) * eps
    if reach > RELIEF_REACH:
        return every
    needed = []
    for collider in colliders:
        rise, cosine = vertex_relief(collider, reach, enough=(1.0 - GAP) * eps)
        needed.append(eps * cosine - rise < GAP * eps)
    return every[np.concatenate(needed)]


@wp.kernel
def vertex_boxes(tested: wp.array(dtype=int), points: wp.array(dtype=wp.vec3), velocities: wp.array(dtype=wp.vec3),
                 dt: float, margin: float, lower: wp.array(dtype=wp.vec3), upper: wp.array(dtype=wp.vec3)):
    """The box over the step of each ``tested`` body vertex, grown by ``margin`` [m]."""
    i = wp.tid()
    p = points[tested[i]]
    q = p + velocities[tested[i]] * dt
    lower[i] = wp.min(p, q) - wp.vec3(margin)
    upper[i] = wp.max(p, q) + wp.vec3(margin)


@wp.kernel
def gather_body_vertices(
    first: int,
    x: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    thickness: wp.array(dtype=float),
    tris: wp.array(dtype=int, ndim=2),
    bvh: wp.uint64,
    tested: wp.array(dtype=int),
    body_q: wp.array(dtype=wp.vec3),
    body_qd: wp.array(dtype=wp.vec3),
    dt: float,
    margin: float,
    everything: int,
    continuing: int,
    ref: wp.array(dtype=wp.vec3, ndim=2),
    ref_step: wp.array(dtype=wp.vec3, ndim=2),
    searched_again: wp.array(dtype=int),
    ignored_parts: wp.array(dtype=int),
    vertex_parts: wp.array(dtype=int),
    out: wp.array(dtype=int, ndim=2),
    out_count: wp.array(dtype=int),
    out_distance: wp.array(dtype=float, ndim=2),
    overflow: wp.array(dtype=int),
):
    """The body vertices (``tested[item]`` for the items of ``bvh``) whose boxes (grown by
    ``margin``, half the search margin) meet cloth triangle t's box over the step grown by eps
    and ``margin``, and that lie no farther from the triangle than eps, the search margin and
    both steps: until the next search each moves at most half the margin beyond its step (the
    reasoning of :func:`~party.collision.cloth.keep_candidate`). The nearest MAX_VERTICES are kept, and the
    nodes' places in ``ref`` and their steps in ``ref_step``. With ``everything`` 0 only
    triangles with a node whose step left the region searched for it
    (:func:`~party.collision.body.covered`) search again (the body must be static then, or
    ``continuing``); with ``continuing`` 1 their nodes are marked in ``searched_again``.
    Vertices of the body parts all three nodes pass through (``ignored_parts``,
    ``vertex_parts``) are not kept."""
    t = first + wp.tid()
    a = tris[t, 0]
    b = tris[t, 1]
    c = tris[t, 2]
    if everything == 0:
        complete = out_count[t] < MAX_VERTICES
        if (covered(x[a], v[a], dt, ref[t, 0], ref_step[t, 0], margin, continuing, complete)
                and covered(x[b], v[b], dt, ref[t, 1], ref_step[t, 1], margin, continuing, complete)
                and covered(x[c], v[c], dt, ref[t, 2], ref_step[t, 2], margin, continuing, complete)):
            return
    if continuing != 0:
        searched_again[a] = 1
        searched_again[b] = 1
        searched_again[c] = 1
    ref[t, 0] = x[a]
    ref[t, 1] = x[b]
    ref[t, 2] = x[c]
    ref_step[t, 0] = v[a] * dt
    ref_step[t, 1] = v[b] * dt
    ref_step[t, 2] = v[c] * dt
    eps = wp.max(thickness[a], wp.max(thickness[b], thickness[c]))
    lo = wp.min(wp.min(wp.min(x[a], x[b]), x[c]), wp.min(wp.min(x[a] + v[a] * dt, x[b] + v[b] * dt), x[c] + v[c] * dt))
    hi = wp.max(wp.max(wp.max(x[a], x[b]), x[c]), wp.max(wp.max(x[a] + v[a] * dt, x[b] + v[b] * dt), x[c] + v[c] * dt))
    query = wp.bvh_query_aabb(bvh, lo - wp.vec3(eps + margin), hi + wp.vec3(eps + margin))
    reach = eps + 2.0 * margin + triangle_step(a, b, c, v, dt)
    item = int(0)
    count = int(0)
    ignored = ignored_parts[a] & ignored_parts[b] & ignored_parts[c]
    while wp.bvh_query_next(query, item):
        p = tested[item]
        if (vertex_parts[p] & ignored) != 0:
            continue
        w = closest_point_barycentric(body_q[p], x[a], x[b], x[c])
        dist = wp.length(body_q[p] - interpolate(w, x[a], x[b], x[c]))
        if dist > reach + wp.length(body_qd[p]) * dt:
            continue
        count = keep_nearest(t, p, dist, count, MAX_VERTICES, out, out_distance, overflow)
    out_count[t] = count


@wp.func
def facing_normal(d: wp.vec3, normal: wp.vec3, crease_normals: wp.array(dtype=wp.vec3, ndim=2), p: int) -> wp.vec3:
    """The body's normal at vertex p for a cloth point at ``d`` from it [m]: the vertex
    ``normal``, or on a crease whichever of it and the faces' normals there
    (``crease_normals[p]``, zero-padded) faces the point most. The vertex normal of a rim
    points half out, half up; a cloth point over the flat top, pushed along it, slid outward
    step by step and the large-step solver's Cusick specimens were pulled off the pedestal."""
    best = normal
    along = wp.dot(d, normal)
    for k in range(crease_normals.shape[1]):
        c = crease_normals[p, k]
        if wp.length_sq(c) > 0.0 and wp.dot(d, c) > along:
            best = c
            along = wp.dot(d, c)
    return best


@wp.kernel
def respond_body_vertices(
    x: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    thickness: wp.array(dtype=float),
    tris: wp.array(dtype=int, ndim=2),
    body_q: wp.array(dtype=wp.vec3),
    body_qd: wp.array(dtype=wp.vec3),
    vertex_normals: wp.array(dtype=wp.vec3),
    crease_normals: wp.array(dtype=wp.vec3, ndim=2),
    candidates: wp.array(dtype=int, ndim=2),
    candidate_count: wp.array(dtype=int),
    dt: float,
    settled: wp.array(dtype=int),
    contact_face: wp.array(dtype=int),
    faces: wp.array(dtype=int, ndim=2),
    dv: wp.array(dtype=wp.vec3),
    dx: wp.array(dtype=wp.vec3),
    hits: wp.array(dtype=int),
):
    """For cloth triangle t, the candidate vertex whose step ends nearest (the cloth point over
    it at height s + (v_q - v_p) . n_p dt below the gap, :data:`GAP` eps; n_p the vertex
    normal, on a crease the face normal there that faces the point, :func:`facing_normal`), among those under the
    triangle (off it sideways by no more than the body response's tolerance,
    :data:`~party.collision.body.EDGE_TOLERANCE` eps) and no deeper than eps behind the vertex:
    stop the point's approach and move its start out so that the step ends at the gap,
    accumulated into ``dv``, ``dx``, ``hits``. A node resting on the body (within :data:`RESTING`
    eps of the plane of its ``contact_face``, one of ``faces``) takes the part of its share that
    would lift it off that face as a move of its start instead (the same end of step): carried
    as a velocity into the next step, the solve pulled the node back onto the face and the
    response lifted it again, step after step, the node keeping some 80 mm/s that it never
    moved, and denim Cusick specimens chattered at the pedestal's rim through the whole of their
    settling. Skips a triangle without candidates, and one whose nodes the last pass left
    ``settled`` (see :meth:`~party.collision.pipeline.CollisionPipeline.apply`)."""
    t = wp.tid()
    if candidate_count[t] == 0:
        return
    a = tris[t, 0]
    b = tris[t, 1]
    c = tris[t, 2]
    if settled[a] == 1 and settled[b] == 1 and settled[c] == 1:
        return
    eps = wp.max(thickness[a], wp.max(thickness[b], thickness[c]))
    gap = GAP * eps
    face = wp.cross(x[b] - x[a], x[c] - x[a])
    if wp.length(face) == 0.0:
        return
    face = wp.normalize(face)
    best_end = gap
    best_w = wp.vec3(0.0)
    best_n = wp.vec3(0.0)
    best_un = float(0.0)
    best_s = float(0.0)
    for j in range(candidate_count[t]):
        p = candidates[t, j]
        w = closest_point_barycentric(body_q[p], x[a], x[b], x[c])
        q = interpolate(w, x[a], x[b], x[c])
        offset = body_q[p] - q
        if wp.length(offset - wp.dot(offset, face) * face) > EDGE_TOLERANCE * eps:
            continue
        n = facing_normal(q - body_q[p], vertex_normals[p], crease_normals, p)
        s = wp.dot(q - body_q[p], n)
        if s < -eps:
            continue
        un = wp.dot(interpolate(w, v[a], v[b], v[c]) - body_qd[p], n)
        end = s + un * dt
        if end < best_end:
            best_end = end
            best_w = w
            best_n = n
            best_un = un
            best_s = s
    if best_end >= gap:
        return
    w = best_w
    im = w[0] * w[0] * inv_mass[a] + w[1] * w[1] * inv_mass[b] + w[2] * w[2] * inv_mass[c]
    if im == 0.0:
        return
    dvp = wp.vec3(0.0)
    un = best_un
    if un < 0.0:
        dvp = -un * best_n
        un = 0.0
    dxp = wp.vec3(0.0)
    end = best_s + un * dt
    if end < gap:
        dxp = (gap - end) * best_n
    w2 = wp.dot(w, w)
    for k in range(3):
        node = tris[t, k]
        if inv_mass[node] > 0.0 and w[k] > 0.0:
            dvk = w[k] / w2 * dvp
            dxk = w[k] / w2 * dxp
            f = contact_face[node]
            if f >= 0:
                m = face_normal(f, faces, body_q)
                lift = wp.max(wp.dot(dvk, m), 0.0)
                if lift > 0.0 and wp.dot(x[node] - body_q[faces[f, 0]], m) <= RESTING * thickness[node]:
                    dvk -= lift * m
                    dxk += (lift * dt) * m
            wp.atomic_add(dv, node, dvk)
            wp.atomic_add(dx, node, dxk)
            wp.atomic_add(hits, node, 1)
