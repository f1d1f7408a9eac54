"""Air: wind and drag on each cloth triangle, with shielding by cloth upwind.

Force model (a thin flat plate, after the normal-force form used for sails and cloth):
the air velocity relative to a triangle, u = w s - v_tri (w the wind, s the triangle's
shielding factor, v_tri the mean of its nodes' velocities), is split along the triangle's unit
normal n into u_n = (u . n) n and u_t = u - u_n, and

    F = 1/2 rho_air A (C_n |u . n| u_n + C_t |u_t| u_t)

with A the triangle's area. The normal part carries both the drag and the lift of an inclined
plate (its component along u is drag, across u lift); C_n = 1.2 is the normal-force coefficient
of a flat plate broadside to the flow (Hoerner, Fluid-Dynamic Drag, 3-16: 1.17-1.28), and
C_t = 0.02 a skin-friction coefficient. F is shared equally by the three nodes. In still air
the same formula is air drag on moving cloth.

Shielding: every ``shield_interval`` steps a ray is cast upwind from each triangle's centre; a
triangle that sees other cloth (not its own neighbourhood) within ``shield_range`` is in its
wake and feels the wind scaled by ``shielding``. This is how the windward half of the cloth
over the rod shields the leeward half (figure 11).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import warp as wp

from ..launch import launch

wp.set_module_options({"enable_backward": False})  # no adjoints: party never differentiates its kernels


@dataclass(frozen=True)
class Air:
    """Aerodynamic parameters. density [kg/m^3]; coefficients [-]; shield_range [m]."""

    density: float = 1.2
    normal_coefficient: float = 1.2
    tangential_coefficient: float = 0.02
    shielding: float = 0.1
    shield_interval: int = 20
    shield_range: float = 0.5


@wp.kernel
def triangle_air_forces(
    x: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    tris: wp.array(dtype=int, ndim=2),
    shield: wp.array(dtype=float),
    wind: wp.vec3,
    rho_air: float,
    c_n: float,
    c_t: float,
    f: wp.array(dtype=wp.vec3),
):
    t = wp.tid()
    a = tris[t, 0]
    b = tris[t, 1]
    c = tris[t, 2]
    cr = wp.cross(x[b] - x[a], x[c] - x[a])
    twice_area = wp.length(cr)
    if twice_area < 1.0e-20:
        return
    n = cr / twice_area
    area = 0.5 * twice_area
    u = wind * shield[t] - (v[a] + v[b] + v[c]) / 3.0
    un = wp.dot(u, n)
    ut = u - un * n
    force = 0.5 * rho_air * area * (c_n * wp.abs(un) * un * n + c_t * wp.length(ut) * ut)
    share = force / 3.0
    wp.atomic_add(f, a, share)
    wp.atomic_add(f, b, share)
    wp.atomic_add(f, c, share)


@wp.kernel
def triangle_shielding(
    mesh: wp.uint64,
    x: wp.array(dtype=wp.vec3),
    tris: wp.array(dtype=int, ndim=2),
    upwind: wp.vec3,
    max_range: float,
    factor: float,
    shield: wp.array(dtype=float),
):
    t = wp.tid()
    a = tris[t, 0]
    b = tris[t, 1]
    c = tris[t, 2]
    center = (x[a] + x[b] + x[c]) / 3.0
    start = center + upwind * 1.0e-4
    q = wp.mesh_query_ray(mesh, start, upwind, max_range)
    s = float(1.0)
    if q.result:
        hit = q.face
        shares = int(0)
        for k in range(3):
            node = tris[hit, k]
            if node == a or node == b or node == c:
                shares = 1
        if shares == 0 and q.t > 1.0e-3:
            s = factor
    shield[t] = s


class AirForces:
    """Computes the air force on every node for a step (launches only, except the periodic
    shielding update which refits a BVH)."""

    carried = ("shield", "_steps")
    """The shielding last computed and the steps counted towards the next (:mod:`party.solvers.memory`)."""

    def __init__(self, model, air: Air) -> None:
        self.model = model
        self.air = air
        dev = model.device
        self.shield = wp.ones(max(model.triangle_count, 1), dtype=float, device=dev)
        self._points = wp.clone(model.node_rest_points)
        self._mesh = None
        if model.triangle_count:
            self._mesh = wp.Mesh(points=self._points, indices=wp.array(model.triangles.ravel().astype(np.int32),
                                                                        dtype=int, device=dev))
        self._steps = 0

    def accumulate(self, x: wp.array, v: wp.array, wind, f: wp.array) -> None:
        """Add this step's air forces [N] into ``f``."""
        m = self.model
        if m.triangle_count == 0:
            return
        wind = wp.vec3(*wind)
        speed = float(np.linalg.norm(np.asarray(wind)))
        if speed > 0.0 and self.air.shielding < 1.0 and self._steps % max(self.air.shield_interval, 1) == 0:
            wp.copy(self._points, x)
            self._mesh.refit()
            launch(triangle_shielding, dim=m.triangle_count,
                   inputs=[self._mesh.id, x, m.triangle_nodes, -wind / speed, self.air.shield_range,
                           self.air.shielding, self.shield], device=m.device)
        self._steps += 1
        launch(triangle_air_forces, dim=m.triangle_count,
               inputs=[x, v, m.triangle_nodes, self.shield, wind, self.air.density,
                       self.air.normal_coefficient, self.air.tangential_coefficient, f], device=m.device)
