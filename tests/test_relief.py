"""Which body vertices the cloth could meet between its nodes: a vertex's rise above the body
around it (exact on a sphere and a cube's corner), and the vertices left untested under a
net much finer than the body's curvature."""

import numpy as np
import pytest
import trimesh

from party.body import box
from party.body.collider import collider_from_trimesh
from party.body.relief import vertex_relief
from party.collision import CollisionPipeline, CollisionSettings
from party.collision.body_vertices import GAP, vertices_to_test
from party.fabric import wool_flannel
from party.meshing import rectangular_net
from party.model import ModelBuilder
from party.solvers import SolverImplicit
from party.solvers.registry import solver_class
from conftest import simulate

RADIUS = 0.3


def sphere():
    return collider_from_trimesh(trimesh.creation.icosphere(subdivisions=4, radius=RADIUS), "sphere")


def test_a_sphere_vertex_rises_by_the_sagitta_over_its_reach():
    """On an icosphere every surface point at distance r from a vertex lies between the
    sphere and its facets' inscribed sphere, so the vertex rises r^2 / 2R above them, and at
    most the facets' depth below the sphere more (and r sin t, where its normal is t off the
    radius)."""
    body = sphere()
    reach = 0.03
    rise, cosine = vertex_relief(body, reach)
    p = body.vertices[body.faces]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    depth = RADIUS - np.abs(np.einsum("ij,ij->i", p[:, 0], normal / np.linalg.norm(normal, axis=1)[:, None])).min()
    sagitta = reach ** 2 / (2 * RADIUS)
    tilt = np.linalg.norm(np.cross(body.vertex_normals(), body.vertices / RADIUS), axis=1)
    assert rise.min() >= 0.99 * sagitta
    assert np.all(rise <= sagitta + depth + reach * tilt + 1e-9)
    assert cosine.min() >= np.cos(np.arcsin(reach / RADIUS) + 0.05)


def test_a_cube_corner_rises_along_the_faces_steepest_descent():
    """At a cube's corner (normal (1, 1, 1) / sqrt 3) the surface falls fastest down a face's
    diagonal, to r sqrt(2/3) at distance r (the faces' interiors, not their corners or edges,
    give it); the faces' normals meet the corner's at cos = 1 / sqrt 3."""
    cube = box((0.2, 0.2, 0.2))
    reach = 0.05
    rise, cosine = vertex_relief(cube, reach)
    assert rise == pytest.approx(np.full(len(cube.vertices), reach * np.sqrt(2 / 3)), rel=1e-9)
    assert cosine == pytest.approx(np.full(len(cube.vertices), 1 / np.sqrt(3)), rel=1e-9)


def cloth_over(body, spacing: float, size: float = 0.3):
    b = ModelBuilder()
    net = rectangular_net(size, size, spacing)
    b.add_cloth(net, wool_flannel(), np.c_[net.uv - size / 2, np.full(net.node_count, RADIUS + 0.01)])
    b.add_collider(body)
    return b.finalize("cpu")


def test_under_a_fine_net_no_vertex_of_a_large_sphere_is_tested_but_a_cone_tip_is():
    """A 16 mm net (eps 3 mm) over a 0.3 m sphere: every vertex rises some 1.6 mm over its
    reach, and the cloth, held eps off the faces, stays more than a gap off it, so the pipeline
    leaves the body vertices out. A cone's tip rises by its whole reach and is tested; its flat
    base's middle is not."""
    model = cloth_over(sphere(), 0.016)
    assert len(vertices_to_test(model)) == 0
    assert not CollisionPipeline(model, CollisionSettings(body_vertices=True)).has_body_vertices
    cone = collider_from_trimesh(trimesh.creation.cone(radius=0.05, height=0.1, sections=16), "cone")
    tested = set(vertices_to_test(cloth_over(cone, 0.016)).tolist())
    tip = int(np.argmax(cone.vertices[:, 2]))
    base_middle = int(np.argmin(np.linalg.norm(cone.vertices, axis=1)))
    assert tip in tested and base_middle not in tested


def test_cloth_on_a_sphere_whose_vertices_are_untested_stays_a_gap_off_them():
    """The 16 mm net falls onto the sphere with the implicit solver and its large-step collision
    (body vertices on, none of them tested): after 0.4 s resting on the top, the cloth over
    every vertex under it is still well over the gap (a quarter of eps) above it."""
    model = cloth_over(sphere(), 0.016)
    solver = SolverImplicit(model, collision=CollisionSettings(body_vertices=True, crossing_guard=True, arrive=True))
    state = simulate(model, solver, int(round(0.4 * 300)), solver_class("implicit").default_dt)
    heights = cloth_heights_over_vertices(state.positions(), model.triangles, sphere())
    eps = wool_flannel().thickness
    assert len(heights) > 50
    assert heights.min() > 2 * GAP * eps


def cloth_heights_over_vertices(points: np.ndarray, triangles: np.ndarray, body) -> np.ndarray:
    """Height [m] of the cloth along each body vertex's normal, for the vertices the cloth is over."""
    normals = body.vertex_normals()
    a, b, c = (points[triangles[:, k]] for k in range(3))
    heights = []
    for p, n in zip(body.vertices, normals):
        e1, e2, s = b - a, c - a, p - a
        q = np.cross(n, e2)
        det = np.einsum("ij,ij->i", e1, q)
        ok = np.abs(det) > 1e-15
        u = np.einsum("ij,ij->i", s, q) / np.where(ok, det, 1.0)
        r = np.cross(s, e1)
        v = (r @ n) / np.where(ok, det, 1.0)
        t = np.einsum("ij,ij->i", e2, r) / np.where(ok, det, 1.0)
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (np.abs(t) < 0.02)
        if hit.any():
            heights.append(t[hit].min())
    return np.array(heights)
