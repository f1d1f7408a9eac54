"""Body vertices against cloth triangles: a body's tip under a triangle's interior, where no
cloth node comes near the body."""

import numpy as np
import pytest
import trimesh

from party.body import box
from party.body.collider import ColliderMesh, collider_from_trimesh
from party.collision import CollisionSettings
from party.collision.body_vertices import GAP
from party.fabric import wool_flannel
from party.meshing import rectangular_net
from party.model import ModelBuilder
from party.solvers import SolverExplicit, SolverImplicit
from party.solvers.registry import solver_class
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

    dt = solver_class(solver).default_dt
    simulate(model, stepper, int(round(0.2 / dt)), dt, every=1, callback=height)
    return heights, fabric.thickness


def test_a_body_tip_under_a_triangle_stays_a_thickness_below_it(solver_name):
    """Without the body vertices' response the cone's tip comes through the triangles (the
    paper's node-against-body test sees nothing: no node is near the cone); with it the
    cloth stops at the gap (a quarter of eps) over the tip and stays there for 0.2 s."""
    through, eps = cloth_over_a_cone(False, solver_name)
    assert min(through) < 0.0
    held, eps = cloth_over_a_cone(True, solver_name)
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


def test_cloth_beside_a_thin_part_of_the_body_is_not_counted():
    """An ear-like fin 4 mm thick (x from -2 to 2 mm) beside a flat cloth wall at x = 6 mm: the
    wall lies behind the far side's 4 corners along their normals, within reach, but outside
    the fin (the cone's tip above counts the cloth behind a vertex inside the body)."""
    from party.output.metrics import body_vertices_through

    fin = box((0.004, 0.04, 0.04), center=(0.0, 0.0, 0.02), name="ear")
    net = rectangular_net(0.1, 0.1, 0.01)
    wall = np.c_[np.full(net.node_count, 0.006), net.uv - (0.05, 0.03)]
    assert body_vertices_through(wall, net.triangles, [fin]) == 0


def test_a_body_vertex_buried_in_another_part_of_the_body_is_not_counted():
    """A torso box with an arm box run 2 cm into it (one collider, two closed shells, as a body
    mesh's arm meets its torso at the armpit) over a cloth sheet under the arm: the torso's
    corners inside the arm have the sheet's edge behind them within reach, but it is outside
    the body."""
    from party.output.metrics import body_vertices_through

    torso, arm = box((0.1, 0.1, 0.1)), box((0.17, 0.12, 0.06), center=(0.115, 0.0, 0.07))
    body = ColliderMesh("body", np.vstack([torso.vertices, arm.vertices]),
                        np.vstack([torso.faces, arm.faces + len(torso.vertices)]))
    net = rectangular_net(0.24, 0.2, 0.01)
    sheet = np.c_[net.uv + (0.06, -0.1), np.full(net.node_count, 0.035)]
    assert body_vertices_through(sheet, net.triangles, [body]) == 0


def test_the_body_searched_again_only_where_a_node_left_its_region_misses_nothing():
    """A 0.3 m cloth (2 cm net) falling 5 mm onto the cone's tip and sliding off it, 1 s of
    implicit steps, the body searched again only for the nodes (cloth triangles) that may have
    left the region searched for them: at each of a step's Collision()s (the first, and one to
    ``CONTACT_ROUNDS`` after the plastic limit) each node still holds every body triangle, and
    each cloth triangle every body vertex, that a search of its step alone (no margin) finds,
    though most searches were left out."""
    import warp as wp

    from party.collision.body import MAX_FACES, gather_body_faces_bvh
    from party.collision.body_vertices import MAX_VERTICES, gather_body_vertices
    from party.solvers.implicit.solver import CONTACT_ROUNDS

    net = rectangular_net(0.3, 0.3, 0.02)
    b = ModelBuilder()
    b.add_cloth(net, wool_flannel(), np.c_[net.uv - 0.15, np.full(net.node_count, TIP[2] + 0.005)])
    b.add_collider(collider_from_trimesh(trimesh.creation.cone(radius=0.05, height=0.1, sections=16), "cone"))
    model = b.finalize("cpu")
    solver = SolverImplicit(model, collision=CollisionSettings(body_vertices=True))
    n, t = model.node_count, model.triangle_count
    faces, face_count = wp.zeros((n, MAX_FACES), dtype=int), wp.zeros(n, dtype=int)
    vertices, vertex_count = wp.zeros((t, MAX_VERTICES), dtype=int), wp.zeros(t, dtype=int)
    distance, overflow = wp.zeros((t, MAX_VERTICES), dtype=float), wp.zeros(1, dtype=int)
    counts = {"searched": 0, "possible": 0, "needed": 0, "missing": 0, "continuing": 0}
    references = [solver.collision._body_ref.numpy().copy()]  # where each node was last searched from

    def checked(self, x, v, state, dt, continuing):
        before, now = references[-1], self._body_ref.numpy().copy()
        references.append(now)
        counts["searched"] += int(np.any(now != before, axis=1).sum())
        counts["possible"] += n
        counts["continuing"] += int(continuing)
        unused = wp.zeros(n, dtype=int)
        wp.launch(gather_body_faces_bvh, dim=n, inputs=[0, x, v, model.node_inv_mass, model.node_thickness,
                                                        self.body_tree.id, dt, 0.0, 1, 0, wp.zeros(n, dtype=wp.vec3),
                                                        wp.zeros(n, dtype=wp.vec3), unused,
                                                        model.node_ignored_parts, model.collider_face_parts, faces,
                                                        face_count, overflow])
        wp.launch(gather_body_vertices, dim=t, inputs=[0, x, v, model.node_thickness, model.triangle_nodes,
                                                       self._vertex_tree.id, self.tested_vertices, state.collider_q,
                                                       state.collider_qd, dt,
                                                       0.0, 1, 0, wp.zeros((t, 3), dtype=wp.vec3),
                                                       wp.zeros((t, 3), dtype=wp.vec3), unused,
                                                       model.node_ignored_parts, model.collider_vertex_parts, vertices,
                                                       vertex_count, distance, overflow])
        pairs = ((faces, face_count, self.body_faces, self.body_face_count),
                 (vertices, vertex_count, self.body_vertices, self.body_vertex_count))
        for fresh, fresh_count, held, held_count in pairs:
            fresh, fresh_count, held, held_count = fresh.numpy(), fresh_count.numpy(), held.numpy(), held_count.numpy()
            for k in np.flatnonzero(fresh_count):
                need = set(fresh[k, :fresh_count[k]].tolist())
                counts["needed"] += len(need)
                counts["missing"] += len(need - set(held[k, :held_count[k]].tolist()))

    solver.collision.after_body_search = checked
    state = simulate(model, solver, 300, solver_class("implicit").default_dt)
    assert state.positions()[:, 2].min() < 0.05  # it slid off the tip
    assert overflow.numpy()[0] == 0
    assert counts["needed"] > 1000 and counts["missing"] == 0
    assert counts["searched"] < 0.5 * counts["possible"]
    assert 300 <= counts["continuing"] <= 300 * CONTACT_ROUNDS


def test_cloth_pressed_onto_a_rim_is_pushed_up_off_its_vertices_not_outward():
    """A 4 cm square of cloth lying flat half an eps over a drum's rim (its middle over a rim
    vertex, the outer half beyond the rim) is pressed down by a whole eps in a step. The rim
    vertex's normal points half out, half up; pushed along it, cloth on a pedestal slid
    outward step by step. Across a crease the response takes the face normal that faces the
    cloth: the top's, so every node keeps its place and velocity across, the nodes over the
    top end at eps and the cloth over the vertex at the gap."""
    import warp as wp

    from party.collision.pipeline import CollisionPipeline

    fabric = wool_flannel()
    eps = fabric.thickness
    drum = trimesh.creation.cylinder(radius=0.1, height=0.2, sections=24)
    drum.apply_translation((0.0, 0.0, -0.1))
    net = rectangular_net(0.04, 0.04, 0.04)
    b = ModelBuilder()
    b.add_cloth(net, fabric, np.c_[net.uv + (0.08, -0.02), np.full(net.node_count, 0.5 * eps)])
    b.add_collider(collider_from_trimesh(drum, "drum"))
    model = b.finalize("cpu")
    dt = 1.0 / 300.0
    pipeline = CollisionPipeline(model, CollisionSettings(cloth=False, body_vertices=True))
    state = model.state()
    x = wp.clone(state.node_q)
    v = wp.array(np.tile([0.0, 0.0, -eps / dt], (model.node_count, 1)), dtype=wp.vec3, device="cpu")
    pipeline.apply(x, v, state, dt)
    start, velocity = x.numpy(), v.numpy()
    assert np.all(start[:, :2] == state.positions()[:, :2])
    assert np.all(velocity[:, :2] == 0.0)
    end = start + velocity * dt
    over_top = np.linalg.norm(end[:, :2], axis=1) < 0.1
    assert np.all(end[over_top, 2] >= eps * (1 - 1e-4))
    rim_vertex = np.array([0.1, 0.0, 0.0])
    assert min(height_over(end[t], rim_vertex) for t in model.triangles) >= GAP * eps * (1 - 1e-4)


def test_a_node_resting_on_the_body_is_lifted_for_a_vertex_by_position_not_velocity():
    """A 4 cm square of cloth resting at eps on a drum's top with its outer half draped down
    past the rim, the outer nodes pulled down so that the cloth over a rim vertex would end
    below the gap. The vertex's response lifts the cloth there; the nodes resting on the top
    take their share of the lift as a move of their start, not as a velocity away from the top:
    carried into the next step, such a velocity had the solve pull the node back each step and
    the response lift it again, and denim Cusick specimens chattered at the pedestal's rim for
    the whole 300 s of their settling. The step still ends with the cloth at the gap over the
    vertex and the resting nodes at eps or above."""
    import warp as wp

    from party.collision.pipeline import CollisionPipeline

    fabric = wool_flannel()
    eps = fabric.thickness
    dt = 1.0 / 300.0
    drum = trimesh.creation.cylinder(radius=0.1, height=0.2, sections=24)
    drum.apply_translation((0.0, 0.0, -0.1))
    net = rectangular_net(0.04, 0.04, 0.04)
    xy = net.uv + (0.08, -0.02)
    inner = xy[:, 0] < 0.1
    b = ModelBuilder()
    b.add_cloth(net, fabric, np.c_[xy, np.where(inner, eps, -0.4 * eps)])
    b.add_collider(collider_from_trimesh(drum, "drum"))
    model = b.finalize("cpu")
    pipeline = CollisionPipeline(model, CollisionSettings(cloth=False, body_vertices=True))
    state = model.state()
    settle = np.where(inner[:, None], [0.0, 0.0, -0.1 * eps / dt], 0.0)
    pipeline.apply(wp.clone(state.node_q), wp.array(settle, dtype=wp.vec3, device="cpu"), state, dt)
    assert np.all((pipeline.body_contact_face.numpy() >= 0) == inner)  # the inner nodes rest on the top
    x = wp.clone(state.node_q)
    v = wp.array(np.where(inner[:, None], 0.0, [0.0, 0.0, -0.5 * eps / dt]), dtype=wp.vec3, device="cpu")
    pipeline.apply(x, v, state, dt)
    start, velocity = x.numpy(), v.numpy()
    assert np.all(velocity[inner, 2] <= 0.0)
    assert start[inner, 2].max() > eps * (1 + 1e-3)  # lifted, by position
    end = start + velocity * dt
    assert np.all(end[inner, 2] >= eps * (1 - 1e-4))
    rim_vertex = np.array([0.1, 0.0, 0.0])
    assert min(height_over(end[t], rim_vertex) for t in model.triangles) >= GAP * eps * (1 - 1e-4)
