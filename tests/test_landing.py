"""Steps cut into substeps where cloth lands on a body (party.collision.landing)."""

import dataclasses
import math

import numpy as np
import pytest

from party.body import floor, sphere
from party.collision import CollisionSettings
from party.collision.landing import LANDING_REACH, MAX_LANDING_SUBSTEPS, shortest_edge
from party.collision.pipeline import CollisionPipeline
from party.errors import SimulationUnstable
from party.fabric import fabric_by_name
from party.units import GRAVITY
from party.meshing import rectangular_net
from party.model import ModelBuilder
from party.solvers.registry import make_solver

SPACING = 0.02  # m, the net's warp and weft elements: its shortest
DT = 1.0 / 150.0


def sheet_over(collider, height: float):
    """A 10 cm square of cotton at ``height`` [m] over ``collider``; its model and pipeline."""
    net = rectangular_net(0.1, 0.1, SPACING)
    builder = ModelBuilder()
    builder.add_cloth(net, fabric_by_name("cotton"), np.c_[net.uv - 0.05, np.full(net.node_count, height)])
    builder.add_collider(collider)
    model = builder.finalize("cpu")
    return model, CollisionPipeline(model, CollisionSettings(broad_phase="bvh"))


def substeps_for(start, end_of_step, relative_to=(0.0, 0.0, 0.0)) -> int:
    """The substeps of LANDING_REACH of the net's spacing for a node whose velocity [m/s] is
    ``start`` at the step's start and ``end_of_step`` at its end, relative to a body moving at
    ``relative_to``."""
    fastest = max(np.linalg.norm(np.subtract(start, relative_to)),
                  np.linalg.norm(np.subtract(end_of_step, relative_to)))
    return math.ceil(fastest * DT / (LANDING_REACH * SPACING))


def after_gravity(velocity) -> np.ndarray:
    return np.asarray(velocity, dtype=float) + np.array([0.0, 0.0, -GRAVITY]) * DT


@pytest.mark.parametrize("velocity", [(0, 0, -3.0), (0, 0, -5.0), (4.0, 0, -0.5), (0, 0, -40.0)])
def test_a_step_reaching_the_body_is_cut_so_no_node_moves_more_than_half_an_element(velocity):
    """The node's motion is taken at the velocity gravity gives it by the step's end, where
    that is faster."""
    model, pipeline = sheet_over(floor(0.0), 0.01)
    state = model.state(velocity=np.tile(velocity, (model.node_count, 1)))
    expected = substeps_for(velocity, after_gravity(velocity))
    assert 1 < expected <= MAX_LANDING_SUBSTEPS
    assert pipeline.landing_substeps(state, DT) == expected


def test_a_step_that_stays_off_the_body_or_moves_little_is_not_cut():
    model, pipeline = sheet_over(floor(0.0), 0.5)
    assert pipeline.landing_substeps(model.state(velocity=np.tile((0, 0, -3.0), (model.node_count, 1))), DT) == 1
    model, pipeline = sheet_over(floor(0.0), 0.01)
    slow = LANDING_REACH * SPACING / DT * 0.99 - GRAVITY * DT
    assert pipeline.landing_substeps(model.state(velocity=np.tile((0, 0, -slow), (model.node_count, 1))), DT) == 1


def test_cloth_at_rest_over_a_body_is_cut_for_what_gravity_gives_it_within_a_long_step():
    """A sheet at rest 1 cm over the floor, in one step of 0.1 s, falls 9.8 cm by implicit
    Euler's step: it must be cut though it starts still. (Judged by the start alone, a 16 x 16
    sheet dropped onto the sphere in steps of 0.3 s was stretched to 2.0 times rest.)"""
    model, pipeline = sheet_over(floor(0.0), 0.01)
    dt = 0.1
    assert pipeline.landing_substeps(model.state(), dt) == math.ceil(GRAVITY * dt * dt / (LANDING_REACH * SPACING))


def test_a_step_that_would_need_more_substeps_than_the_most_is_refused_with_the_step_that_would_do():
    model, pipeline = sheet_over(floor(0.0), 0.01)
    fast = 1.5 * MAX_LANDING_SUBSTEPS * LANDING_REACH * SPACING / DT
    state = model.state(velocity=np.tile((0, 0, -fast), (model.node_count, 1)))
    needed = substeps_for((0, 0, -fast), after_gravity((0, 0, -fast)))
    with pytest.raises(SimulationUnstable) as refused:
        pipeline.landing_substeps(state, DT)
    assert str(refused.value) == (
        f"a step of {DT:g} s is too long for cloth meeting the body: landing would take {needed} substeps "
        f"(at most {MAX_LANDING_SUBSTEPS}); use a step of at most {DT * MAX_LANDING_SUBSTEPS / needed:.2g} s (--dt)")


def test_a_body_moving_into_resting_cloth_cuts_the_step_by_their_relative_speed():
    rising = dataclasses.replace(floor(0.0), velocity=np.array([0.0, 0.0, 3.0]))
    model, pipeline = sheet_over(rising, 0.01)
    still = (0.0, 0.0, 0.0)
    assert pipeline.landing_substeps(model.state(), DT) == substeps_for(still, after_gravity(still), (0, 0, 3.0))
    with_it = model.state(velocity=np.tile((0, 0, 3.0), (model.node_count, 1)))
    assert pipeline.landing_substeps(with_it, DT) == 1


def test_a_tie_shorter_than_the_net_does_not_set_the_reach():
    """A sewing spring of 0.1 mm between two nodes of the net leaves their reach the net's
    spacing, the shortest edge of their triangles."""
    net = rectangular_net(0.1, 0.1, SPACING)
    builder = ModelBuilder()
    builder.add_cloth(net, fabric_by_name("cotton"), np.c_[net.uv, np.zeros(net.node_count)])
    builder.add_springs(np.array([[0, 7]]), stiffness=100.0, rest_length=1e-4)
    model = builder.finalize("cpu")
    assert shortest_edge(model) == pytest.approx(np.full(model.node_count, SPACING))


def warp_weft_stretch(grid: int, dt: float, seconds: float, landing: bool) -> np.ndarray:
    """A 1 m square of ``grid`` x ``grid`` cotton nodes dropped 0.32 m onto a sphere of 0.3 m
    in steps of ``dt`` [s] (as ``party run sphere-drop``): its warp and weft elements' lengths
    over rest after ``seconds``."""
    net = rectangular_net(1.0, 1.0, 1.0 / (grid - 1))
    builder = ModelBuilder()
    builder.add_cloth(net, fabric_by_name("cotton"), np.c_[net.uv - 0.5, np.full(net.node_count, 0.62)])
    builder.add_collider(sphere(0.3, subdivisions=4))
    model = builder.finalize("cpu")
    solver = make_solver("implicit", model, collision=CollisionSettings(cloth=False, landing=landing))
    state, scratch, control = model.state(), model.state(), model.control()
    for _ in range(int(round(seconds / dt))):
        solver.step(state, scratch, control, dt)
        state, scratch = scratch, state
    elements = model.host.elements
    rest = model.host.element_rest_length
    warp_weft = np.isclose(rest, rest.min())
    points = state.positions()
    length = np.linalg.norm(points[elements[:, 1]] - points[elements[:, 0]], axis=1)
    assert np.linalg.norm(points, axis=1).min() > 0.3  # on the sphere, not in it
    return (length / rest)[warp_weft]


def test_a_sheet_dropped_in_large_steps_lands_without_being_stretched_to_the_plastic_limit():
    """At 1/150 s a node of the 64 x 64 sheet moves 1.7 cm a step when it lands, more than its
    1.6 cm elements: without substeps, 3 % of the warp and weft elements were held beyond 9 %
    (the plastic limit is 10 %) after 1 s; with them, 0.4 % (at 1/1,200 s none, the largest
    1.026 times rest)."""
    cut = warp_weft_stretch(64, DT, 1.0, True)
    whole = warp_weft_stretch(64, DT, 1.0, False)
    assert (cut > 1.09).mean() < 0.01
    assert (whole > 1.09).mean() > 0.02
    assert (cut > 1.05).mean() < 0.5 * (whole > 1.05).mean()


def test_a_sheet_dropped_in_steps_of_a_third_of_a_second_stays_within_its_plastic_limit():
    """Three steps of 0.3 s take the 16 x 16 sheet from 0.32 m above the sphere to lying on it;
    the landing substeps keep every warp and weft element within cotton's limit (10 %; judged
    by each step's start alone, the sheet was stretched to 2.0 times rest)."""
    limit = 1.0 + fabric_by_name("cotton").strain_limit
    assert warp_weft_stretch(16, 0.3, 0.9, True).max() <= limit * (1.0 + 1e-4)
