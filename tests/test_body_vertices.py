"""Body vertices against cloth triangles: a body's tip under a triangle's interior, where no
cloth node comes near the body."""

import numpy as np
import pytest
import trimesh

from party.body.collider import collider_from_trimesh
from party.collision import CollisionSettings
from party.collision.body_vertices import GAP
from party.fabric import wool_flannel
from party.meshing import rectangular_net
from party.model import ModelBuilder
from party.solvers import SolverExplicit, SolverImplicit
from party.solvers.select import DEFAULT_DT
from conftest import simulate

TIP = np.array([0.0, 0.0, 0.1])


def height_over(corners: np.ndarray, point: np.ndarray) -> float:
    """The height [m] of a triangle over ``point``'s (x, y), or infinity if it is not over it."""
    a, b, c = corners
    m = np.array([b[:2] - a[:2], c[:2] - a[:2]]).T
    u, v = np.linalg.solve(m, point[:2] - a[:2])
    if min(u, v, 1.0 - u - v) < -1e-9:
        return np.inf
    return float(a[2] + u * (b[2] - a[2]) + v * (c[2] - a[2]))


def cloth_over_a_cone(body_vertices: bool, solver: str) -> tuple[list[float], float]:
    """A 0.3 m square of two triangles falling from 5 mm above the tip of a cone (radius
    5 cm, height 10 cm) under its middle: every node stays 10 cm or more from the cone.
    Returns the cloth's height above the tip after each step [m] and eps."""
    fabric = wool_flannel()
    net = rectangular_net(0.3, 0.3, 0.3)
    b = ModelBuilder()
    b.add_cloth(net, fabric, np.c_[net.uv - 0.15, np.full(net.node_count, TIP[2] + 0.005)])
    b.add_collider(collider_from_trimesh(trimesh.creation.cone(radius=0.05, height=0.1, sections=16), "cone"))
    model = b.finalize("cpu")
    stepper = {"implicit": SolverImplicit, "explicit": SolverExplicit}[solver](
        model, collision=CollisionSettings(body_vertices=body_vertices))
    heights = []

    def height(state, step):
        p = state.positions()
        heights.append(min(height_over(p[t], TIP) for t in model.triangles) - TIP[2])

    dt = DEFAULT_DT[solver] if solver == "implicit" else 1e-4
    simulate(model, stepper, int(round(0.2 / dt)), dt, every=1, callback=height)
    return heights, fabric.thickness


@pytest.mark.parametrize("solver", ["implicit", "explicit"])
def test_a_body_tip_under_a_triangle_stays_a_thickness_below_it(solver):
    """Without the body vertices' response the cone's tip comes through the triangles (the
    paper's node-against-body test sees nothing: no node is near the cone); with it the
    cloth stops at the gap (a quarter of eps) over the tip and stays there for 0.2 s."""
    through, eps = cloth_over_a_cone(False, solver)
    assert min(through) < 0.0
    held, eps = cloth_over_a_cone(True, solver)
    gap = GAP * eps
    assert min(held) >= 0.99 * gap
    assert held[-1] == pytest.approx(gap, abs=0.1 * gap)


@pytest.mark.parametrize("height,through", [(0.01, 0), (-0.01, 1)])
def test_a_body_vertex_is_counted_through_the_cloth_when_the_cloth_lies_behind_it(height, through):
    """A flat square ``height`` [m] over the cone's tip (the other vertices 9 cm and more away,
    beyond the 2 cm reach): the tip counts only when the cloth lies below it."""
    from party.output.metrics import body_vertices_through

    net = rectangular_net(0.3, 0.3, 0.05)
    points = np.c_[net.uv - 0.15, np.full(net.node_count, TIP[2] + height)]
    cone = collider_from_trimesh(trimesh.creation.cone(radius=0.05, height=0.1, sections=16), "cone")
    assert body_vertices_through(points, net.triangles, [cone]) == through
