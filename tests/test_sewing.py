"""Sewing: a tube sewn from two panels closes around a cylinder; relaxation lowers the energy
monotonically to a plateau."""

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from party.body import Body, rod
from party.body.probe import ColliderProbe
from party.fabric import wool_flannel
from party.garment.assemble import assemble
from party.pattern import EdgeRef, Panel, Pattern, Placement, Seam, euler_xyz_degrees, line

W, H, R = 0.35, 0.30, 0.15


def tube_pattern():
    pts = np.array([[0, 0], [W, 0], [W, H], [0, H]])
    edges = tuple(line(pts[k], pts[(k + 1) % 4]) for k in range(4))
    front = Placement(np.array([-W / 2, -R, 0.0]), euler_xyz_degrees([90, 0, 0]), wrap_radius=R)
    back = Placement(np.array([W / 2, R, 0.0]), euler_xyz_degrees([90, 0, 180]), wrap_radius=R)
    panels = {"front": Panel("front", edges, np.array([0.0, 1.0]), placement=front),
              "back": Panel("back", edges, np.array([0.0, 1.0]), placement=back)}
    seams = (Seam(EdgeRef("front", 1), EdgeRef("back", 3)), Seam(EdgeRef("front", 3), EdgeRef("back", 1)))
    return Pattern("tube", panels, seams)


@pytest.fixture(scope="module")
def sewn_tube():
    from party.garment.sewing import SewingSettings, sew

    body = Body("cylinder", (rod(0.8, 0.08, center=(0, 0, 0.15), axis=(0, 0, 1)),), {"shoulder": 0.3})
    garment = assemble(tube_pattern(), 0.02)
    return sew(garment, body, wool_flannel(), SewingSettings(max_iterations=3000)), body


def test_tube_closes_around_the_cylinder(sewn_tube):
    sewn, body = sewn_tube
    assert sewn.max_seam_gap < 2e-3
    assert ColliderProbe(body.colliders).penetrations(sewn.points) == 0
    e = sewn.net.elements
    graph = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(sewn.net.node_count,) * 2)
    assert connected_components(graph, directed=False)[0] == 1
    radius = np.hypot(sewn.points[:, 0], sewn.points[:, 1])
    assert radius.min() > 0.08
    # the sewn tube's girth is the two panels' widths (within the strain the seams cost)
    circumference = 2 * W
    assert np.median(radius) == pytest.approx(circumference / (2 * np.pi), rel=0.08)


def test_relaxation_energy_falls_monotonically_to_a_plateau(sewn_tube):
    sewn, _ = sewn_tube
    energy = np.array(sewn.relaxation.energy)[:, 1]  # the sewing phase
    start = energy[0]
    assert start > 1e4 * energy[-1]
    # falls at every logged iteration, up to contact noise a hundred-thousandth of the start
    assert np.all(np.diff(energy) <= 1e-5 * start)
    tail = energy[-6:]
    assert tail.max() - tail.min() < 1e-5 * start
