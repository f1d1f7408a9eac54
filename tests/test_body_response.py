"""Cloth against body: eqs. (8)-(12) exactly, thickness, no tunnelling."""

import numpy as np
import pytest

from party.body import box, floor, sphere
from party.collision import CollisionSettings
from party.errors import InvalidInput
from party.fabric import wool_flannel
from party.model import ModelBuilder
from party.solvers.registry import solver_class
from conftest import simulate

MU, SIGMA, EPS, DT = 0.6, 0.03, 3.0e-3, 1.0e-4


def paper_response(v, n, mu, sigma, v_body):
    """Eqs. (8)-(12) written out with NumPy."""
    vr = v - v_body
    un = vr @ n
    vn = un * n
    vt = vr - vn
    if np.linalg.norm(vt) < mu * abs(un):
        vt = np.zeros(3)
    else:
        vt = vt * (1 - mu * abs(un) / np.linalg.norm(vt))
    return vt - sigma * vn + v_body


def node_over_floor(velocity, floor_velocity=(0.0, 0.0, 0.0), height=0.005, solver="explicit", dt=DT,
                    collision=CollisionSettings(cloth=False)):
    fabric = wool_flannel()
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    b.add_node((0.0, 0.0, height), 1e-4, fabric=fabric)
    slab = floor(0.0, size=2.0)
    b.add_collider(type(slab)(slab.name, slab.vertices, slab.faces, np.asarray(floor_velocity, float)))
    model = b.finalize("cpu")
    integrator = solver_class(solver)(model, collision=collision)
    state, out = model.state(velocity=velocity), model.state()
    integrator.step(state, out, model.control(), dt)
    return out


@pytest.mark.parametrize("velocity", [
    (1.0, 0.5, -30.0),   # inside the friction cone: sticks
    (25.0, 0.0, -30.0),  # outside: slides, |v_t| reduced by mu |v_n|
    (0.0, 0.0, -30.0),   # head-on
])
def test_static_floor_response_is_eqs_8_to_12(velocity, solver_name):
    out = node_over_floor(velocity, solver=solver_name)
    expected = paper_response(np.array(velocity), np.array([0, 0, 1.0]), MU, SIGMA, np.zeros(3))
    assert np.allclose(out.velocities()[0], expected, atol=1e-4)
    assert out.positions()[0, 2] >= EPS - 1e-6


@pytest.mark.parametrize("arrive", [False, True])
def test_a_node_stopped_by_the_body_bounces_from_where_its_step_reached_the_shell(arrive, solver_name):
    """A node 5 mm over the floor at 30 m/s down, a step of 1e-4 s taking it 3 mm, into the
    shell eps = 3 mm thick: as printed the response leaves it where it started and it ends
    its step at 5 mm plus its bounce, sigma 30 m/s dt; with ``arrive`` (the implicit solver's
    large steps) it is first moved to eps, where its step reached the shell, and ends at eps
    plus the bounce. Its velocity is eqs. (8)-(12)'s either way."""
    velocity = (1.0, 0.5, -30.0)
    out = node_over_floor(velocity, solver=solver_name, collision=CollisionSettings(cloth=False, arrive=arrive))
    bounce = SIGMA * 30.0 * DT
    assert out.positions()[0, 2] == pytest.approx((EPS if arrive else 0.005) + bounce, abs=1e-6)
    expected = paper_response(np.array(velocity), np.array([0, 0, 1.0]), MU, SIGMA, np.zeros(3))
    assert np.allclose(out.velocities()[0], expected, atol=1e-4)


def test_inside_and_outside_cone_differ_as_the_paper_says(solver_name):
    stick = node_over_floor((10.0, 0.0, -30.0), solver=solver_name).velocities()[0]
    slide = node_over_floor((20.0, 0.0, -30.0), solver=solver_name).velocities()[0]
    assert stick[0] == pytest.approx(0.0, abs=1e-5)
    assert slide[0] == pytest.approx(20.0 - MU * 30.0, rel=1e-4)


def test_moving_body_velocity_is_added_back(solver_name):
    v_floor = np.array([2.0, -1.0, 0.5])
    out = node_over_floor((15.0, 3.0, -30.0), floor_velocity=v_floor, solver=solver_name)
    expected = paper_response(np.array([15.0, 3.0, -30.0]), np.array([0, 0, 1.0]), MU, SIGMA, v_floor)
    assert np.allclose(out.velocities()[0], expected, atol=1e-4)


def test_large_step_friction_cone_is_the_papers():
    """The implicit solver at a 1/300 s step: the same cone decides sticking and sliding."""
    for velocity in [(0.5, 0.2, -1.5), (2.0, 0.0, -1.5)]:
        out = node_over_floor(velocity, solver="implicit", dt=1.0 / 300.0, height=0.006)
        expected = paper_response(np.array(velocity), np.array([0, 0, 1.0]), MU, SIGMA, np.zeros(3))
        assert np.allclose(out.velocities()[0], expected, atol=1e-4)
        assert out.positions()[0, 2] >= EPS - 1e-6


def test_fast_node_does_not_tunnel_through_thin_plate(solver_name):
    """A 1 mm plate; the node moves 5 mm per step (50 m/s), more than eps per step and more
    than the plate is thick."""
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    b.add_node((0.0, 0.0, 0.05), 1e-4, fabric=wool_flannel())
    b.add_collider(box((0.5, 0.5, 0.001), center=(0, 0, 0)))
    model = b.finalize("cpu")
    integrator = solver_class(solver_name)(model, collision=CollisionSettings(cloth=False))
    state, out = model.state(velocity=(0.3, 0.0, -50.0)), model.state()
    for _ in range(40):
        integrator.step(state, out, model.control(), DT)
        state, out = out, state
    z = state.positions()[0, 2]
    assert z >= 0.0005 + EPS - 1e-6


def test_resting_node_stays_eps_above_under_gravity(solver_name):
    dt = solver_class(solver_name).default_dt
    steps = round(0.3 / dt)
    b = ModelBuilder()
    b.add_node((0.0, 0.0, 0.01), 1e-4, fabric=wool_flannel())
    b.add_collider(floor(0.0))
    model = b.finalize("cpu")
    state = simulate(model, solver_class(solver_name)(model, collision=CollisionSettings(cloth=False)), steps, dt)
    # within half of one step's free fall g dt^2 (0.1 mm at 1/300 s, 0.05 um at 1e-4 s) or 10 um
    assert state.positions()[0, 2] == pytest.approx(EPS, abs=max(1e-5, 0.5 * 9.81 * dt * dt))
    assert abs(state.velocities()[0, 2]) < 0.05


@pytest.mark.parametrize("vertices,faces,message", [
    (np.zeros((0, 3)), np.zeros((0, 3), int), "is empty"),
    (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1.0]]),
     np.array([[0, 1, 2], [0, 1, 3], [0, 1, 4]]), "non-manifold"),
    (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]), np.array([[0, 1, 5]]), "face index out of range"),
    (np.array([[0, 0, np.nan], [1, 0, 0], [0, 1, 0.0]]), np.array([[0, 1, 2]]), "non-finite"),
])
def test_bad_collider_meshes(vertices, faces, message):
    from party.body import ColliderMesh

    with pytest.raises(InvalidInput, match=message):
        ColliderMesh("prop", vertices, faces)


def test_inward_normals_are_refused():
    from party.body import ColliderMesh

    b = box((1, 1, 1))
    with pytest.raises(InvalidInput, match="inward-facing normals"):
        ColliderMesh("inside-out", b.vertices, b.faces[:, ::-1])


def test_a_second_collision_of_a_step_searches_the_body_again_where_a_step_left_its_region():
    """A node 20 mm over a floor stepping 10 mm down (no floor triangle within reach): a second
    Collision() of the same step (``continuing``, as after the plastic limit) whose step now
    reaches 30 mm down searches the floor again for that node, marks it searched again (its
    first pass may not take over the first Collision()'s settled state), and stops its
    approach (reusing the candidates, it went through the floor); one whose step, shortened,
    stays within the box searched searches nothing."""
    import warp as wp

    from party.collision.pipeline import CollisionPipeline

    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    b.add_node((0.0, 0.0, 0.02), 1e-4, fabric=wool_flannel())
    b.add_collider(floor(0.0, size=2.0))
    model = b.finalize("cpu")
    collision = CollisionPipeline(model, CollisionSettings(cloth=False, broad_phase="bvh"))
    state, dt = model.state(), 1.0 / 300.0
    x = wp.array([[0.0, 0.0, 0.02]], dtype=wp.vec3, device="cpu")

    def step_down(length: float) -> wp.array:
        return wp.array([[0.0, 0.0, -length / dt]], dtype=wp.vec3, device="cpu")

    collision.apply(x, step_down(0.01), state, dt)
    assert collision.body_face_count.numpy()[0] == 0
    shortened = step_down(0.006)
    collision.apply(x, shortened, state, dt, continuing=True)
    assert collision.body_face_count.numpy()[0] == 0 and collision._searched_again.numpy()[0] == 0
    through = step_down(0.03)
    collision.apply(x, through, state, dt, continuing=True)
    assert collision.body_face_count.numpy()[0] > 0 and collision._searched_again.numpy()[0] == 1
    assert through.numpy()[0, 2] >= 0.0  # the approach stopped (eqs. 8-12: restitution sends it back up)
    assert x.numpy()[0, 2] + through.numpy()[0, 2] * dt >= EPS


def test_a_complete_list_of_body_candidates_serves_the_next_step_within_the_box_searched():
    """Between steps a node keeps its body candidates while its step stays within the box of
    the step searched for, where the search kept all it found: a node 20 mm over a floor that
    stepped 10 mm down keeps them for a step of 6 mm from the same place (beyond half the margin
    of where it was searched from), and one reaching 30 mm down, through the floor, searches
    again and is stopped. Over a finely meshed sphere, where the search found more triangles
    than a list holds, a shortened step searches again."""
    import warp as wp

    from party.collision.body import MAX_FACES
    from party.collision.pipeline import CollisionPipeline

    dt = 1.0 / 300.0

    def pipeline(collider, height):
        b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
        b.add_node((0.0, 0.0, height), 1e-4, fabric=wool_flannel())
        b.add_collider(collider)
        model = b.finalize("cpu")
        collision = CollisionPipeline(model, CollisionSettings(cloth=False, broad_phase="bvh"))
        return model.state(), wp.array([[0.0, 0.0, height]], dtype=wp.vec3, device="cpu"), collision

    def step_down(length: float) -> wp.array:
        return wp.array([[0.0, 0.0, -length / dt]], dtype=wp.vec3, device="cpu")

    state, x, collision = pipeline(floor(0.0, size=2.0), 0.02)
    collision.apply(x, step_down(0.01), state, dt)
    assert collision.body_face_count.numpy()[0] == 0
    assert 0.006 > 0.5 * collision.body_margin
    collision.apply(x, step_down(0.006), state, dt)
    assert np.allclose(collision._body_step_ref.numpy()[0], [0.0, 0.0, -0.01])
    through = step_down(0.03)
    collision.apply(x, through, state, dt)
    assert collision.body_face_count.numpy()[0] > 0 and through.numpy()[0, 2] >= 0.0
    assert x.numpy()[0, 2] + through.numpy()[0, 2] * dt >= EPS

    state, x, collision = pipeline(sphere(0.1, subdivisions=6), 0.108)
    collision.apply(x, step_down(0.004), state, dt)
    assert collision.body_face_count.numpy()[0] == MAX_FACES
    collision.apply(x, step_down(0.003), state, dt)
    assert np.allclose(collision._body_step_ref.numpy()[0], [0.0, 0.0, -0.003])
