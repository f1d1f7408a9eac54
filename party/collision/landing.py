"""How finely a large step must be cut where cloth lands on a body (ours, for large steps).

A node that reaches a body within a step stops there, while its neighbours, not yet there,
move on for the rest of the step: over a step in which a node moves farther than about half
its elements' length, the element between them is stretched to the plastic limit in that one
step, and friction on the pressure of the stretched cloth then holds the stretch. Smaller steps
everywhere would cure it at their cost everywhere; cutting only the steps in which a node near
the body would move farther than :data:`LANDING_REACH` of its shortest edge relative to the body
spends the substeps where cloth lands.

A node's motion over the step is taken at both ends of the step: its velocity at the start and
that velocity plus what gravity adds over the step. Judged by the start alone, cloth at rest
over a body would never be cut, and a step long enough for it to fall far would stretch it
many times over.
"""

from __future__ import annotations

import numpy as np
import warp as wp

from ..model import Model
from .geometry import step_box

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels

LANDING_REACH = 0.5
"""Largest distance, in units of the node's shortest edge (:func:`shortest_edge`), that a
node near a body may move relative to it in one (sub)step."""

MAX_LANDING_SUBSTEPS = 100
"""Most substeps a step is cut into for landing cloth; a step that would need more is refused
(:class:`~party.errors.SimulationUnstable`) rather than cut short of what it needs; a
hundred is far beyond what a frame's step needs and bounds the step's cost."""


@wp.kernel
def largest_speed(v: wp.array(dtype=wp.vec3), speed: wp.array(dtype=float)):
    """Raise ``speed[0]`` to the largest |v| [m/s] (a body's vertices)."""
    wp.atomic_max(speed, 0, wp.length(v[wp.tid()]))


@wp.kernel
def landing_substeps(x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), inv_mass: wp.array(dtype=float),
                     thickness: wp.array(dtype=float), length: wp.array(dtype=float), bvh: wp.uint64,
                     faces: wp.array(dtype=int, ndim=2), body_qd: wp.array(dtype=wp.vec3),
                     body_speed: wp.array(dtype=float), gravity: wp.vec3, dt: float, margin: float, reach: float,
                     most: wp.array(dtype=int)):
    """Raise ``most[0]`` to the substeps a step of ``dt`` [s] needs so that node i, where its step
    (grown by its thickness and ``margin`` [m]) meets the box of a body triangle in the BVH (swept
    over the body's step), moves no more than ``reach`` times its shortest edge ``length``
    [m] relative to that triangle per substep. The node's step is taken at its velocity ``v``
    and at that velocity plus ``gravity`` [m/s^2] times ``dt``, whichever is faster relative to
    the triangle. A node that cannot move so far relative to any body, slower than that by more
    than the bodies' fastest vertex (``body_speed[0]`` [m/s]), does not search."""
    i = wp.tid()
    if inv_mass[i] == 0.0:
        return
    allowed = reach * length[i]
    vi = v[i]
    v_end = vi + gravity * dt
    if (wp.max(wp.length(vi), wp.length(v_end)) + body_speed[0]) * dt <= allowed:
        return
    lo0, hi0 = step_box(x[i], vi * dt, thickness[i] + margin)
    lo1, hi1 = step_box(x[i], v_end * dt, thickness[i] + margin)
    lo = wp.min(lo0, lo1)
    hi = wp.max(hi0, hi1)
    query = wp.bvh_query_aabb(bvh, lo, hi)
    f = int(0)
    needed = int(1)
    while wp.bvh_query_next(query, f):
        body_v = (body_qd[faces[f, 0]] + body_qd[faces[f, 1]] + body_qd[faces[f, 2]]) / 3.0
        relative = wp.max(wp.length(vi - body_v), wp.length(v_end - body_v))
        needed = wp.max(needed, int(wp.ceil(relative * dt / allowed)))
    if needed > 1:
        wp.atomic_max(most, 0, needed)


def shortest_edge(model: Model) -> np.ndarray:
    """Each node's shortest edge at rest [m]: of its cloth triangles (the net's spacing, not a
    tie such as a sewing spring), or of its elements where it has no triangle; infinite for a
    node with neither (it is never cut for)."""
    h = model.host
    length = np.full(model.node_count, np.inf)
    tri = h.triangles.astype(np.int64).reshape(-1, 3)
    if len(tri):
        inverse = model.triangle_inv_rest.numpy().astype(np.float64)
        ok = np.linalg.det(inverse) != 0.0  # a degenerate triangle's inverse was left 0
        edges = np.linalg.inv(inverse[ok])  # columns: the rest edges e1, e2 [m]
        sides = np.full(len(tri), np.inf)
        sides[ok] = np.linalg.norm(np.stack([edges[:, :, 0], edges[:, :, 1], edges[:, :, 1] - edges[:, :, 0]],
                                            axis=1), axis=2).min(axis=1)
        for corner in range(3):
            np.minimum.at(length, tri[:, corner], sides)
    e, rest = h.elements.astype(np.int64), h.element_rest_length.astype(np.float64)
    alone = np.isinf(length)
    for end in range(2):
        bare = alone[e[:, end]] & (rest > 0.0)
        np.minimum.at(length, e[bare, end], rest[bare])
    return length
