"""Untangling crossed layers (intersection contour minimisation)."""

import numpy as np
from scipy.interpolate import griddata

from party.collision.untangle import untangle
from party.meshing import rectangular_net
from party.output.metrics import cloth_crossings


def two_sheets_one_poked_through(depth: float = 3.0e-3):
    """Two 10 cm sheets 2 mm apart, the upper one's middle node pushed ``depth`` [m] below
    the lower one: a pocket of the upper sheet through the lower."""
    net = rectangular_net(0.1, 0.1, 0.01)
    flat = np.c_[net.uv, np.zeros(net.node_count)]
    upper = flat + [0.003, 0.003, 0.002]  # offset, so that no node lies on the other's edges
    middle = int(np.argmin(np.linalg.norm(net.uv - 0.05, axis=1)))
    upper[middle, 2] = -depth
    points = np.concatenate([flat, upper])
    triangles = np.concatenate([net.triangles, net.triangles + net.node_count])
    return points, triangles, net.node_count + middle


def test_a_pocket_through_a_layer_is_moved_back_to_its_own_side():
    points, triangles, tip = two_sheets_one_poked_through()
    assert cloth_crossings(points, triangles) > 0
    untangled, left = untangle(points, triangles)
    assert left == 0 and cloth_crossings(untangled, triangles) == 0
    lower = untangled[: len(points) // 2]
    below_tip = griddata(lower[:, :2], lower[:, 2], untangled[tip, :2][None], method="linear")[0]
    assert untangled[tip, 2] > below_tip  # back above the lower sheet, as the rest of its own
    moved = np.linalg.norm(untangled - points, axis=1)
    far = np.linalg.norm(points[:, :2] - points[tip, :2], axis=1) > 0.03
    assert moved[far].max() == 0.0  # only the crossing's neighbourhood moves
    assert moved.max() < 0.01


def test_nodes_that_are_not_free_stay():
    points, triangles, tip = two_sheets_one_poked_through()
    free = np.ones(len(points), bool)
    free[: len(points) // 2] = False  # the lower sheet is held
    untangled, left = untangle(points, triangles, free)
    assert left == 0
    np.testing.assert_array_equal(untangled[~free], points[~free])
    assert untangled[tip, 2] > 0.0


def test_an_untangled_cloth_is_left_as_it_is():
    points, triangles, tip = two_sheets_one_poked_through()
    points[tip, 2] = 0.002
    untangled, left = untangle(points, triangles)
    assert left == 0
    np.testing.assert_array_equal(untangled, points)
