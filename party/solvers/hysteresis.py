"""Bending hysteresis (Kawabata's 2HB): a Jenkins element beside each thread's bending stencil.

Beside its bending stiffness k, each thread stencil (:mod:`party.meshing.hinges`; not the
twist stencils, so that the frictional moment is HB whichever way the cloth bends) carries a spring
of stiffness ``Model.hinge_friction`` = f k in series with a slider: energy
f k |c - c_slip|^2 / 2 with c the stencil's curvature vector. While |f k (c - c_slip)| stays
below ``Model.hinge_slip_limit`` (HB times the stencil's area) the element sticks; beyond, it
slips, dragging c_slip along so that the moment stays at HB per unit width. Under cyclic bending
the moment traces Kawabata's bilinear loop of width 2HB; at rest the cloth holds any shape
where its bending moment lies within HB of equilibrium.

c_slip is kept in the stencil's own frame (along its thread, its normal, across) so that it
turns with the cloth, and is updated after each step from the step's end (:func:`update_slip`).
The explicit solver takes the stiffness f k with the bending (``Model.bending_matrix()``) and
the slip as a constant force per step, f k K_i c_slip on node i (:func:`slip_forces`). The
implicit solver takes the element into its solve (:func:`slider_moment`, the Huber energy
of backward Euler's return mapping with c_slip at the step's start): a force lagged by a
large step fed back on itself and grew without bound.
"""

from __future__ import annotations

import warp as wp

from ..launch import launch
from ..model import Model, State
from .explicit.kernels import stencil_curvature

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels


@wp.func
def stencil_frame(x: wp.array(dtype=wp.vec3), n: wp.vec4i) -> wp.mat33:
    """Rows: unit vector along the stencil, the normal of the plane its nodes span, across."""
    along = x[n[2]] - x[n[0]]
    side = x[n[3]] - x[n[0]]
    normal = wp.cross(along, side)
    if wp.length(normal) < 1.0e-12 * wp.length(along) * wp.length(side) or wp.length(along) == 0.0:
        return wp.identity(n=3, dtype=float)
    t = wp.normalize(along)
    nn = wp.normalize(normal)
    return wp.matrix_from_rows(t, nn, wp.cross(nn, t))


@wp.kernel
def slip_forces(
    x: wp.array(dtype=wp.vec3),
    hinge_nodes: wp.array(dtype=wp.vec4i),
    hinge_weights: wp.array(dtype=wp.vec4),
    hinge_friction: wp.array(dtype=float),
    slip: wp.array(dtype=wp.vec3),
    f: wp.array(dtype=wp.vec3),
):
    """f_i += friction K_i c_slip [N] (c_slip turned into the world frame)."""
    h = wp.tid()
    s = hinge_friction[h]
    if s == 0.0:
        return
    n = hinge_nodes[h]
    w = hinge_weights[h]
    c_slip = wp.transpose(stencil_frame(x, n)) * slip[h]
    for c in range(4):
        wp.atomic_add(f, n[c], s * w[c] * c_slip)


@wp.kernel
def slip_in_world(
    x: wp.array(dtype=wp.vec3),
    hinge_nodes: wp.array(dtype=wp.vec4i),
    hinge_friction: wp.array(dtype=float),
    slip: wp.array(dtype=wp.vec3),
    slip_world: wp.array(dtype=wp.vec3),
):
    """c_slip turned from the stencil's frame at ``x`` into the world frame [1/m]."""
    h = wp.tid()
    if hinge_friction[h] > 0.0:
        slip_world[h] = wp.transpose(stencil_frame(x, hinge_nodes[h])) * slip[h]


@wp.func
def slider_moment(curvature: wp.vec3, c_slip: wp.vec3, friction: float, limit: float) -> wp.vec3:
    """The Jenkins element's generalized force with its slider returned to the limit:
    friction (k - c_slip) while that stays within ``limit``, else ``limit`` along it
    (the gradient of a Huber energy of k, convex, whose curvature is at most ``friction``)."""
    moment = friction * (curvature - c_slip)
    size = wp.length(moment)
    if size > limit:
        moment = moment * (limit / size)
    return moment


@wp.kernel
def update_slip(
    x: wp.array(dtype=wp.vec3),
    hinge_nodes: wp.array(dtype=wp.vec4i),
    hinge_weights: wp.array(dtype=wp.vec4),
    hinge_friction: wp.array(dtype=float),
    hinge_slip_limit: wp.array(dtype=float),
    slip_in: wp.array(dtype=wp.vec3),
    slip_out: wp.array(dtype=wp.vec3),
):
    """After a step: where the element's force exceeds its limit, slide c_slip towards c
    until it equals the limit."""
    h = wp.tid()
    s = hinge_friction[h]
    if s == 0.0:
        slip_out[h] = slip_in[h]
        return
    n = hinge_nodes[h]
    frame = stencil_frame(x, n)
    c_slip = wp.transpose(frame) * slip_in[h]
    stretch = stencil_curvature(x, n, hinge_weights[h]) - c_slip
    force = s * wp.length(stretch)
    limit = hinge_slip_limit[h]
    if force > limit:
        c_slip = c_slip + stretch * ((force - limit) / force)
    slip_out[h] = frame * c_slip


class BendingHysteresis:
    """The slip forces and the slip update of a model's hysteresis elements (does nothing for
    models without)."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.active = model.hinge_count > 0 and float(model.host.hinge_friction.max(initial=0.0)) > 0.0

    def add_forces(self, state: State, f: wp.array) -> None:
        """Add the slip's constant forces at ``state`` to ``f`` [N]."""
        if self.active:
            m = self.model
            launch(slip_forces, dim=m.hinge_count,
                   inputs=[state.node_q, m.hinge_nodes, m.hinge_weights, m.hinge_friction, state.hinge_slip, f],
                   device=m.device)

    def update(self, state_in: State, state_out: State) -> None:
        """Carry the slip from ``state_in`` to ``state_out``, slipping where the step bent the
        cloth beyond the limit."""
        m = self.model
        if self.active:
            launch(update_slip, dim=m.hinge_count,
                   inputs=[state_out.node_q, m.hinge_nodes, m.hinge_weights, m.hinge_friction, m.hinge_slip_limit,
                           state_in.hinge_slip, state_out.hinge_slip], device=m.device)
