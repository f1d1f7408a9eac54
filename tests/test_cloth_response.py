"""Cloth against cloth: eqs. (13)-(14) exactly, neighbours excluded, layers kept apart."""

import numpy as np
import pytest
import warp as wp

from party.body import box, sphere
from party.collision import CollisionSettings, pipeline
from party.errors import InvalidInput
from party.fabric import wool_flannel
from party.meshing import rectangular_net
from party.model import ModelBuilder
from party.output.metrics import body_penetrations, cloth_crossings, collider_inside_and_distance
from party.solvers import SolverExplicit
from party.solvers.registry import make_solver, solver_class
from conftest import simulate

DT = 1.0e-4
GAMMA, KAPPA = 0.5, 0.23


def node_hits_triangle_vertex(v0, v1=(0.0, 0.0, 0.0), gamma=GAMMA, kappa=KAPPA):
    """A lone node moving straight at vertex a of a free triangle (a node-node case: the
    struck point has barycentric weights (1, 0, 0)). Gravity off, no springs act. Returns the
    velocities after one step, the node's index and the masses [kg]."""
    fabric = wool_flannel().with_(momentum_propagation=gamma, cloth_friction=kappa, tensile_warp=1e-9,
                                  tensile_weft=1e-9, damping=0.0)
    net = rectangular_net(0.02, 0.02, 0.02)  # one quad: 4 nodes, 2 triangles
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    b.add_cloth(net, fabric, np.c_[net.uv, np.zeros(4)])
    hitter = b.add_node((0.0, 0.0, 0.004), 2.3e-5 , fabric=fabric)
    model = b.finalize("cpu")
    velocity = np.zeros((5, 3))
    velocity[:4] = v1
    velocity[hitter] = v0
    state, out = model.state(velocity=velocity), model.state()
    SolverExplicit(model, collision=CollisionSettings(body=False, passes=1)).step(state, out, model.control(), DT)
    return out.velocities(), hitter, model.host.mass


def test_eqs_13_14_node_node():
    v0 = np.array([0.0, 0.0, -20.0])
    v, hitter, _ = node_hits_triangle_vertex(v0)
    assert np.allclose(v[hitter], KAPPA * GAMMA * v0, atol=1e-5)           # (13)
    assert np.allclose(v[0], KAPPA * (0.0 + (1 - GAMMA) * v0), atol=1e-5)  # (14)
    assert np.allclose(v[1:4], 0.0, atol=1e-6)


def test_exchange_is_taken_in_the_struck_points_frame():
    """With the struck node moving too, eqs. (13)-(14) apply to the velocity relative to it."""
    v0, v1 = np.array([0.0, 3.0, -20.0]), np.array([0.0, 1.0, -2.0])
    v, hitter, _ = node_hits_triangle_vertex(v0, v1)
    assert np.allclose(v[hitter], v1 + KAPPA * GAMMA * (v0 - v1), atol=1e-4)
    assert np.allclose(v[0], v1 + KAPPA * (1 - GAMMA) * (v0 - v1), atol=1e-4)


def test_free_exchange_stops_the_approach_and_keeps_the_sliding():
    """gamma = kappa = 1 (the sewing's settling, ``SewingSettings().exchange``): eqs. (13)-(14) change
    nothing, and the approach left is stopped along the normal, momentum kept; the sliding stays."""
    from party.garment.sewing import SewingSettings

    v0 = np.array([0.0, 3.0, -20.0])
    v, hitter, mass = node_hits_triangle_vertex(v0, gamma=SewingSettings().exchange[0], kappa=SewingSettings().exchange[1])
    assert v[hitter][2] == pytest.approx(v[0][2], abs=1e-5)  # no approach left
    assert mass[hitter] * v[hitter][2] + mass[0] * v[0][2] == pytest.approx(mass[hitter] * v0[2], rel=1e-5)
    assert v[hitter][:2] == pytest.approx(v0[:2], abs=1e-5) and np.allclose(v[0][:2], 0.0, atol=1e-6)
    assert np.allclose(v[1:4], 0.0, atol=1e-6)


def test_mesh_neighbours_are_excluded():
    """A node of a quad shooting through the quad's other triangle is not a collision."""
    fabric = wool_flannel()
    net = rectangular_net(0.02, 0.02, 0.02)
    velocity = np.zeros((4, 3))
    velocity[0] = (0.0, 0.0, -20.0)
    results = []
    for settings in (CollisionSettings(body=False), None):
        b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
        b.add_cloth(net, fabric, np.c_[net.uv, np.zeros(4)])
        model = b.finalize("cpu")
        state, out = model.state(velocity=velocity), model.state()
        SolverExplicit(model, collision=settings).step(state, out, model.control(), DT)
        results.append(out.velocities())
    assert np.array_equal(results[0], results[1])


def stacked_cloths(layers: int, push: float, collider, size=0.2, spacing=0.0125, top=0.06, gap=0.012):
    b = ModelBuilder()
    fabric = wool_flannel()
    net = rectangular_net(size, size, spacing)
    for k in range(layers):
        angle = 0.3 * k
        rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        xy = (net.uv - size / 2) @ rot.T
        b.add_cloth(net, fabric, np.c_[xy, np.full(net.node_count, top + k * gap)], name=f"layer{k}")
    b.add_collider(collider)
    model = b.finalize("cpu")
    velocity = np.zeros((model.node_count, 3))
    velocity[:, 2] = -push
    return model, velocity


def stepped(solver, model, velocity: np.ndarray, dt: float, steps: int) -> np.ndarray:
    """Positions and velocities (stacked) after each of ``steps`` steps of ``solver`` from the
    set-up at ``velocity`` [m/s]."""
    state, scratch = model.state(velocity=velocity), model.state()
    control = model.control()
    frames = []
    for _ in range(steps):
        solver.step(state, scratch, control, dt)
        state, scratch = scratch, state
        frames.append(np.concatenate([state.positions(), state.velocities()]))
    return np.array(frames)


@pytest.mark.parametrize("layers,push", [(2, 0.0), (3, 1.0)])
def test_stacked_layers_stay_outside_the_body_and_each_other(layers, push):
    top_face = 0.04
    model, velocity = stacked_cloths(layers, push, box((0.1, 0.1, 0.08), center=(0, 0, 0.0)))
    solver = SolverExplicit(model, collision=CollisionSettings(passes=layers + 1))
    state, scratch = model.state(velocity=velocity), model.state()
    control = model.control()
    colliders = model.host.colliders
    for frame in range(8):
        for _ in range(500):
            solver.step(state, scratch, control, DT)
            state, scratch = scratch, state
        p = state.positions()
        assert body_penetrations(p, colliders) == 0
        assert cloth_crossings(p, model.triangles) == 0
    p = state.positions()
    cloths = model.host.cloths
    centre_heights = [p[c.node_start:c.node_end][c.net.node_count // 2, 2] for c in cloths]
    eps = wool_flannel().thickness
    assert centre_heights[0] >= top_face + eps - 1e-5
    assert np.all(np.diff(centre_heights) >= eps * 0.9)  # in order, a thickness apart


def test_cloth_square_comes_to_rest_on_a_sphere():
    radius = 0.1
    ball = sphere(radius)
    model, velocity = stacked_cloths(1, 0.0, ball, size=0.3, spacing=0.015, top=radius + 0.02)
    solver = SolverExplicit(model, collision=CollisionSettings())
    state = simulate(model, solver, 8000, DT)
    p = state.positions()
    inside, distance = collider_inside_and_distance(p, ball)
    eps = wool_flannel().thickness
    assert not inside.any()
    assert distance.min() >= eps - 2e-4  # the icosphere's chords vs the true sphere
    centre = p[model.node_count // 2]
    assert centre[2] == pytest.approx(radius + eps, abs=1.5e-3)
    assert p[:, 2].min() < 0.0  # the corners have fallen past the equator: it draped


def test_nodes_within_reach_are_the_shortest_paths_shorter_than_it():
    """Model.node_near against scipy's Dijkstra on a net of 3 mm with 3 mm cloth."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    from party.model.builder import FOLD_REACH
    from party.model.nearby import nodes_within

    net = rectangular_net(0.03, 0.03, 0.003)
    rest = net.element_rest_lengths()
    reach = np.full(net.node_count, FOLD_REACH * 0.003)
    offsets, near = nodes_within(net.elements, rest, reach, net.node_count)
    graph = coo_matrix((rest, (net.elements[:, 0], net.elements[:, 1])), shape=(net.node_count,) * 2)
    distance = dijkstra(graph.tocsr(), directed=False)
    for i in range(net.node_count):
        expected = np.flatnonzero(distance[i] < reach[i])
        assert sorted(near[offsets[i]:offsets[i + 1]].tolist()) == [k for k in expected if k != i]
    assert np.diff(offsets).min() == 3 and np.diff(offsets).max() == 8  # a corner's, an inner node's


@pytest.mark.parametrize("spacing", [0.002, 0.003])
def test_a_net_finer_than_its_thickness_does_not_push_itself_apart(solver_name, spacing):
    """A flat sheet of 3 mm cloth meshed at 2 or 3 mm, at rest, no gravity: its own
    triangles lie within the thickness of each node, but no cloth could fold back that
    close, so none is a contact and no node moves (it moved 1.3 and 3 mm in three implicit
    steps when they were)."""
    from party.solvers.registry import solver_class

    fabric = wool_flannel()
    assert fabric.thickness == 0.003
    net = rectangular_net(0.1, 0.1, spacing)
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    flat = np.c_[net.uv, np.zeros(net.node_count)]
    b.add_cloth(net, fabric, flat)
    model = b.finalize("cpu")
    solver = make_solver(solver_name, model)
    state, scratch, control = model.state(), model.state(), model.control()
    dt = solver_class(solver_name).dynamics_step(model)  # the explicit one below its stability limit
    for _ in range(3 if solver_name == "implicit" else 30):
        solver.step(state, scratch, control, dt)
        state, scratch = scratch, state
    assert int(solver.collision.contact_count.numpy().sum()) == 0
    assert np.abs(state.positions() - flat).max() < 1e-6


@pytest.mark.parametrize("solver_name,passes", [("explicit", 4), ("implicit", 4), ("implicit", 2)])
def test_passes_leaving_out_what_the_last_pass_left_as_it_was_end_bit_for_bit_as_full_passes(solver_name, passes):
    """Three layers pushed onto a box (body, body vertices and cloth responses in 4 passes, or
    in 2, so that a Collision() may end with passes that still changed nodes, which the
    implicit solver's second Collision() of the step then takes over): the passes that skip
    settled nodes, triangles and contacts end every step exactly where passes over everything
    do."""
    model, velocity = stacked_cloths(3, 1.0, box((0.1, 0.1, 0.08), center=(0, 0, 0.0)))
    dt = DT if solver_name == "explicit" else solver_class("implicit").default_dt
    steps = 600 if solver_name == "explicit" else 60

    def run(skip_settled: bool) -> np.ndarray:
        collision = CollisionSettings(passes=passes, skip_settled=skip_settled)
        return stepped(make_solver(solver_name, model, collision=collision), model, velocity, dt, steps)

    skipping = run(True)
    full = run(False)
    assert np.array_equal(skipping, full)
    assert np.abs(np.diff(full[:, :model.node_count, 2], axis=0)).max() > 1e-4  # the layers move


def two_layers(gap: float, broad_phase: str):
    """Two 0.1 m squares of 1 cm net, ``gap`` [m] apart, no gravity, and a Collision() for them
    without a body, searching the cloth with a 4 mm margin: the net, the model and the
    pipeline."""
    net = rectangular_net(0.1, 0.1, 0.01)
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    for z in (0.0, gap):
        b.add_cloth(net, wool_flannel(), np.c_[net.uv, np.full(net.node_count, z)])
    model = b.finalize("cpu")
    settings = CollisionSettings(body=False, broad_phase=broad_phase, cloth_search_margin=4.0e-3)
    return net, model, pipeline.CollisionPipeline(model, settings)


@pytest.mark.parametrize("broad_phase", ["intervals", "bvh"])
def test_cloth_moving_as_a_whole_keeps_its_cloth_candidates(broad_phase):
    """Two layers 10 mm apart carried sideways and down at 1.34 m/s, 4.5 mm a step (beyond
    half the search margin): no pair comes nearer, so the cloth is searched once and no
    velocity changes; a node of the lower layer then moving 4 mm a step faster than the rest
    toward the upper one makes the next step search again, and the contact is found (its
    velocity changes before it reaches the upper layer)."""
    net, model, collision = two_layers(0.01, broad_phase)
    state = model.state()
    dt = 1.0 / 300.0
    start = model.host.points.astype(np.float32)
    common = np.array([1.2, 0.0, -0.6], np.float32)
    assert np.linalg.norm(common) * dt > 0.5 * collision.cloth_margin
    x = wp.array(start, dtype=wp.vec3, device="cpu")
    v = wp.zeros(model.node_count, dtype=wp.vec3, device="cpu")
    for k in range(25):
        x.assign(start + k * dt * common)
        v.assign(np.tile(common, (model.node_count, 1)))
        collision.apply(x, v, state, dt)
        assert np.array_equal(v.numpy(), np.tile(common, (model.node_count, 1)))
    assert collision.searches == 1
    node = 60  # the middle of the lower layer
    velocities = np.tile(common, (model.node_count, 1))
    velocities[node, 2] += 1.2
    for k in range(25, 28):
        positions = start + k * dt * common
        positions[node, 2] += (k - 24) * dt * 1.2
        x.assign(positions)
        v.assign(velocities)
        collision.apply(x, v, state, dt)
        if not np.array_equal(v.numpy()[node], velocities[node]):
            break
    assert collision.searches == 2
    gap = start[node + net.node_count, 2] - positions[node, 2]
    assert gap > 0.0 and v.numpy()[node, 2] < velocities[node, 2]


@pytest.mark.parametrize("broad_phase", ["intervals", "bvh"])
def test_a_second_collision_of_a_step_searches_again_only_where_a_step_left_the_box_searched(broad_phase):
    """Two layers 20 mm apart, the upper one falling 10 mm a step (nothing within reach): a
    second Collision() of the same step (``continuing``, as after the plastic limit) whose
    steps, shortened, stay within the boxes of the steps searched keeps the candidates
    (though the nodes moved beyond half the margin of where they were searched from); one
    whose steps now reach 30 mm, through the lower layer, searches again, and the layers end
    the step a thickness apart (reusing the candidates, the upper layer went through)."""
    net, model, collision = two_layers(0.02, broad_phase)
    state = model.state()
    dt = 1.0 / 300.0
    upper = np.arange(model.node_count) >= net.node_count
    x = wp.array(model.host.points.astype(np.float32), dtype=wp.vec3, device="cpu")

    def velocities(step: float) -> wp.array:
        v = np.zeros((model.node_count, 3), np.float32)
        v[upper, 2] = -step / dt
        return wp.array(v, dtype=wp.vec3, device="cpu")

    first = velocities(0.01)
    collision.apply(x, first, state, dt)
    assert collision.searches == 1 and np.array_equal(first.numpy(), velocities(0.01).numpy())
    shortened = velocities(0.006)
    collision.apply(x, shortened, state, dt, continuing=True)
    assert collision.searches == 1 and np.array_equal(shortened.numpy(), velocities(0.006).numpy())
    through = velocities(0.03)
    collision.apply(x, through, state, dt, continuing=True)
    assert collision.searches == 2
    ends = x.numpy()[:, 2] + through.numpy()[:, 2] * dt
    assert (ends[upper] - ends[~upper]).min() >= 0.9 * wool_flannel().thickness


@pytest.mark.parametrize("broad_phase", ["intervals", "bvh"])
def test_a_step_proposed_again_from_where_the_cloth_stayed_keeps_its_candidates(broad_phase):
    """Two layers 20 mm apart, the upper one proposing 10 mm down at every step from where it
    stays (cloth held by its plastic limit while each step's solve pulls it on): the next step's
    Collision() keeps the candidates, its steps lying on the step searched for (though each is
    beyond half the margin); a step turned 5 mm sideways, 2.5 mm beyond the motion common to
    both layers and so beyond half the margin of the step searched for, searches again; one
    reaching 30 mm, through the lower layer, too, and the layers end the step a thickness
    apart."""
    net, model, collision = two_layers(0.02, broad_phase)
    state = model.state()
    dt = 1.0 / 300.0
    upper = np.arange(model.node_count) >= net.node_count
    x = wp.array(model.host.points.astype(np.float32), dtype=wp.vec3, device="cpu")

    def velocities(down: float, sideways: float = 0.0) -> wp.array:
        v = np.zeros((model.node_count, 3), np.float32)
        v[upper, 2] = -down / dt
        v[upper, 0] = sideways / dt
        return wp.array(v, dtype=wp.vec3, device="cpu")

    for searches in (1, 1, 1):
        proposed = velocities(0.01)
        collision.apply(x, proposed, state, dt)
        assert collision.searches == searches and np.array_equal(proposed.numpy(), velocities(0.01).numpy())
    assert 0.5 * collision.cloth_margin < 0.0025
    collision.apply(x, velocities(0.01, 0.005), state, dt)
    assert collision.searches == 2
    through = velocities(0.03)
    collision.apply(x, through, state, dt)
    assert collision.searches == 3
    ends = x.numpy()[:, 2] + through.numpy()[:, 2] * dt
    assert (ends[upper] - ends[~upper]).min() >= 0.9 * wool_flannel().thickness


@pytest.mark.parametrize("broad_phase", ["intervals", "bvh"])
def test_a_search_after_the_plastic_limit_covers_the_step_the_held_cloth_proposes_again(broad_phase):
    """Two layers 13 mm apart. A patch of the upper one proposes 10 mm down, and the plastic
    limit (as it were) holds it where it is; in that second Collision() a node elsewhere
    steps 5 mm sideways, beyond both keep tests, and the cloth is searched again. That search
    looks along the patch's proposed step, so the next step's first Collision(), the patch
    proposing 11.5 mm down (1.5 mm short of the lower layer), keeps the candidates, and they
    hold the lower layer: the patch ends the step a thickness above it."""
    net, model, collision = two_layers(0.013, broad_phase)
    state = model.state()
    dt = 1.0 / 300.0
    points = model.host.points
    upper = np.arange(model.node_count) >= net.node_count
    patch = upper & (np.abs(points[:, 0] - 0.05) < 0.015) & (np.abs(points[:, 1] - 0.05) < 0.015)
    odd = np.flatnonzero(upper & (points[:, 0] < 1e-6) & (points[:, 1] < 1e-6))
    assert patch.sum() == 9 and len(odd) == 1
    x = wp.array(points.astype(np.float32), dtype=wp.vec3, device="cpu")

    def velocities(down: float, sideways: float = 0.0) -> wp.array:
        v = np.zeros((model.node_count, 3), np.float32)
        v[patch, 2] = -down / dt
        v[odd, 0] = sideways / dt
        return wp.array(v, dtype=wp.vec3, device="cpu")

    collision.apply(x, velocities(0.01), state, dt)
    held = wp.array((patch | np.isin(np.arange(model.node_count), odd)).astype(np.int32), dtype=int, device="cpu")
    collision.apply(x, velocities(0.0, 0.005), state, dt, continuing=True, changed=held)
    assert collision.searches == 2
    assert 0.5 * collision.cloth_margin < 0.005  # the sideways step leaves both tests
    onward = velocities(0.0115, 0.005)
    collision.apply(x, onward, state, dt)
    assert collision.searches == 2
    ends = x.numpy()[:, 2] + onward.numpy()[:, 2] * dt
    assert ends[patch].min() >= 0.9 * wool_flannel().thickness


@pytest.mark.parametrize("solver_name,steps,push,wide_margin", [("explicit", 1500, 1.0, 4.0e-3),
                                                                  ("implicit", 60, 0.5, 2.0e-3)])
def test_the_cloth_search_margin_changes_how_often_the_cloth_is_searched_not_where_it_goes(solver_name, steps, push,
                                                                                          wide_margin):
    """Three layers pushed onto a box with a wide cloth search margin and one of 0.5 mm: the
    narrow margin searches more often, and every step ends bit for bit where the wide one's
    does. (With no candidate dropped for want of room in either, which would make the lists
    differ: the implicit solver's 1/300 s steps sweep large boxes, and at 1 m/s or with 4 mm some
    were.)"""
    model, velocity = stacked_cloths(3, push, box((0.1, 0.1, 0.08), center=(0, 0, 0.0)))
    dt = DT if solver_name == "explicit" else solver_class("implicit").default_dt

    def run(margin: float) -> tuple[np.ndarray, int]:
        solver = make_solver(solver_name, model, collision=CollisionSettings(passes=4, cloth_search_margin=margin))
        frames = stepped(solver, model, velocity, dt, steps)
        assert solver.collision.candidate_overflow() == 0
        return frames, solver.collision.searches

    (wide, wide_searches), (narrow, narrow_searches) = run(wide_margin), run(0.5e-3)
    assert narrow_searches > wide_searches
    assert np.array_equal(wide, narrow)
    assert np.abs(wide[-1, :model.node_count] - wide[0, :model.node_count]).max() > 0.01  # the layers move


def test_a_negative_search_margin_is_refused():
    with pytest.raises(InvalidInput, match=r"^cloth_search_margin must be at least 0 m, got -0\.001$"):
        CollisionSettings(cloth_search_margin=-1e-3)


@pytest.mark.parametrize("broad_phase", ["intervals", "bvh"])
@pytest.mark.parametrize("spacing, margin", [(0.02, 4.0e-3), (0.004, 1.0e-3)])
def test_the_cloth_search_margin_narrows_where_it_would_list_the_nets_own_layer(spacing, margin, broad_phase):
    """By default the cloth is searched with the body's 4 mm margin, unless a flat net is so
    fine that 4 mm lists its own layer's triangles beyond what a fold can bring: then a quarter
    of its element, under which the net lists none of them."""
    net = rectangular_net(0.2, 0.2, spacing)
    b = ModelBuilder()
    b.add_cloth(net, wool_flannel(), np.c_[net.uv, np.zeros(net.node_count)])
    model = b.finalize("cpu")
    collision = pipeline.CollisionPipeline(model, CollisionSettings(body=False, broad_phase=broad_phase))
    assert collision.cloth_margin == pytest.approx(margin)
    x = model.node_rest_points
    assert collision.listed_per_node(x, margin) == collision.listed_per_node(x, 0.0) == 0.0
    assert (collision.listed_per_node(x, 4.0e-3) > 1.0) == (spacing < 0.01)
