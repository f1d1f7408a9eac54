"""Kernels of the implicit solver around its sweeps (:mod:`.descent`): each step's inertial
target, body planes, and what the solve's result gives the next step."""

import warp as wp

from ...collision.geometry import closest_point_barycentric, interpolate
from .descent import DescentTerms, behind_plane, blend_node

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
    at 3 cm, 6e-8 m at 1 m), and would be lost; a displacement resolves it. Solved in positions,
    a fine stiff cantilever stalls short of its rest shape, the farther the farther it lies from
    the origin.

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
    first, within a quarter of eps beside it. The plane is that of the face the node lies over,
    not the contact face: a node resting between two faces would take the one on one step and
    the other on the next, and the plane of the face beside it, turned round that face's edge,
    would lift it, so that it rocked at every step."""
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


@wp.kernel
def record_correction(disp: wp.array(dtype=wp.vec3), y: wp.array(dtype=wp.vec3), push: wp.array(dtype=wp.vec3),
                      dt: float, correction: wp.array(dtype=wp.vec3)):
    """The solve's correction d - y to the inertial target [m], for the next step's start, less
    what a body plane's reaction gave it (``push`` [m/s] over ``dt``): a node that leaves the
    body starts from where the cloth, not the body, held it."""
    i = wp.tid()
    correction[i] = disp[i] - y[i] - push[i] * dt


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
    :func:`~.descent.blend_node` for every node."""
    blend_node(wp.tid(), x, previous, before, omega, plane_normal)


@wp.kernel
def contact_changes(x_before: wp.array(dtype=wp.vec3), v_before: wp.array(dtype=wp.vec3), x: wp.array(dtype=wp.vec3),
                    v: wp.array(dtype=wp.vec3), inv_mass: wp.array(dtype=float), node_length: wp.array(dtype=float),
                    body_face: wp.array(dtype=int), dt: float, reach: float, held: wp.array(dtype=int),
                    source: wp.array(dtype=int), sources: wp.array(dtype=int)):
    """What the last Collision() did to each node (its start position and velocity were
    ``x_before``, ``v_before``): a node it changed at all is ``held`` from then on within the
    step (flags are only set here), and one off the body (``body_face`` -1) whose end of step
    it moved farther than ``reach`` times the node's shortest edge (``node_length`` [m]) is a
    ``source``, counted in ``sources``. A node on the body is left out: its body plane is in
    the solve already, and what Collision() changes there is mostly friction's slow slip."""
    i = wp.tid()
    source[i] = 0
    if inv_mass[i] == 0.0:
        held[i] = 1
        return
    moved = (x[i] - x_before[i]) + (v[i] - v_before[i]) * dt
    if wp.length_sq(moved) > 0.0 or wp.length_sq(v[i] - v_before[i]) > 0.0:
        held[i] = 1
    if body_face[i] < 0 and wp.length(moved) > reach * node_length[i]:
        source[i] = 1
        wp.atomic_add(sources, 0, 1)


@wp.kernel
def contact_region(offsets: wp.array(dtype=int), neighbours: wp.array(dtype=int), source: wp.array(dtype=int),
                   held: wp.array(dtype=int), rings: int, color_offsets: wp.array(dtype=int),
                   colored: wp.array(dtype=int), depth: wp.array(dtype=int), queue: wp.array(dtype=int),
                   resolved: wp.array(dtype=int), region_offsets: wp.array(dtype=int), region: wp.array(dtype=int)):
    """The nodes a contact re-solve moves: those within ``rings`` rings of neighbours (element and
    bending rows, ``offsets``/``neighbours``) of a ``source`` and not ``held``, flagged in
    ``resolved`` and listed colour by colour (of ``colored``) in ``region`` with their colour
    offsets ``region_offsets``. One thread: the flags reset, a breadth-first search from the
    sources (its work grows with the region, not with the net), then one pass over the colours."""
    n = source.shape[0]
    tail = int(0)
    for i in range(n):
        resolved[i] = 0
        depth[i] = -1
        if source[i] != 0:
            depth[i] = 0
            queue[tail] = i
            tail += 1
    head = int(0)
    while head < tail:
        i = queue[head]
        head += 1
        if held[i] == 0:
            resolved[i] = 1
        if depth[i] < rings:
            for j in range(offsets[i], offsets[i + 1]):
                k = neighbours[j]
                if depth[k] < 0:
                    depth[k] = depth[i] + 1
                    queue[tail] = k
                    tail += 1
    count = int(0)
    region_offsets[0] = 0
    for c in range(color_offsets.shape[0] - 1):
        for j in range(color_offsets[c], color_offsets[c + 1]):
            i = colored[j]
            if resolved[i] != 0:
                region[count] = i
                count += 1
        region_offsets[c + 1] = count


@wp.kernel
def spread_region(offsets: wp.array(dtype=int), neighbours: wp.array(dtype=int), flags: wp.array(dtype=int),
                  held: wp.array(dtype=int), spread: wp.array(dtype=int), resolved: wp.array(dtype=int)):
    """One ring of :func:`contact_region`'s search, a thread per node (for a GPU): ``spread`` is
    ``flags`` grown by one ring of neighbours, and ``resolved`` flags those of its nodes not
    ``held``. Launched ring after ring, it flags what the search does."""
    i = wp.tid()
    reached = flags[i]
    if reached == 0:
        for j in range(offsets[i], offsets[i + 1]):
            if flags[neighbours[j]] != 0:
                reached = 1
                break
    spread[i] = reached
    resolved[i] = 0
    if reached != 0 and held[i] == 0:
        resolved[i] = 1


@wp.kernel
def contact_resolve_start(x_start: wp.array(dtype=wp.vec3), x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3),
                          inv_mass: wp.array(dtype=float), resolved: wp.array(dtype=int), dt: float,
                          solve_inv_mass: wp.array(dtype=float), disp: wp.array(dtype=wp.vec3)):
    """The re-solve's start: every node's displacement over the step as the state has it,
    x + v dt - x(t) [m]; the nodes it does not move (not ``resolved``) are given no inverse
    mass (``solve_inv_mass``), so that sweeps over every node leave them."""
    i = wp.tid()
    disp[i] = x[i] + v[i] * dt - x_start[i]
    solve_inv_mass[i] = 0.0
    if resolved[i] != 0:
        solve_inv_mass[i] = inv_mass[i]


@wp.kernel
def contact_resolved_velocity(x_start: wp.array(dtype=wp.vec3), x: wp.array(dtype=wp.vec3),
                              disp: wp.array(dtype=wp.vec3), resolved: wp.array(dtype=int), dt: float,
                              v: wp.array(dtype=wp.vec3)):
    """The re-solved nodes' velocities, (x(t) + d - x) / dt [m/s] (x, the start Collision()
    left, is x(t) for a node it did not change)."""
    i = wp.tid()
    if resolved[i] != 0:
        v[i] = (x_start[i] + disp[i] - x[i]) / dt
