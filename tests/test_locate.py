"""Where a drape's faults lie: the panel and the stage a failure reason names."""

import numpy as np

from party.output.locate import locate, node_panels
from party.output.metrics import crossing_edges


def two_squares(gap: float = 0.5):
    """Two unit squares side by side in the plane z = 0, panels 'left' and 'right', each of
    two triangles, with their four edges as warp/weft elements of rest length 1 m."""
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    points = np.concatenate([square, square + [1.0 + gap, 0.0, 0.0]])
    triangles = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    ring = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    elements = np.concatenate([ring, ring + 4])
    return points, triangles, elements, np.ones(len(elements)), np.ones(len(elements), bool)


def test_each_node_takes_the_panel_of_its_triangles():
    _, triangles, *_ = two_squares()
    assert node_panels(triangles, np.array([0, 0, 1, 1]), 9).tolist() == [0, 0, 0, 0, 1, 1, 1, 1, -1]


def test_the_most_stretched_element_names_its_panel_and_the_stage_that_stretched_it():
    sewn, triangles, elements, rest, limited = two_squares()
    draped = sewn.copy()
    draped[5, 0] += 0.6  # the right square's element 4-5 at 1.6 times rest, nothing else beyond 1.3
    none = np.zeros(len(sewn), bool)
    args = (elements, rest, limited, none, none, triangles, crossing_edges(draped, triangles), np.array([0, 0, 1, 1]),
            ["left", "right"])
    assert locate(draped, sewn, *args)["stretched"] == {"panels": ["right"], "stage": "draping"}
    assert locate(draped, draped, *args)["stretched"] == {"panels": ["right"], "stage": "sewing"}
    assert "inside" not in locate(draped, sewn, *args) and "crossings" not in locate(draped, sewn, *args)


def test_nodes_inside_the_body_name_their_panels_most_first_and_whether_the_sewing_had_them():
    points, triangles, elements, rest, limited = two_squares()
    inside = np.array([0, 0, 0, 1, 1, 1, 1, 0], bool)
    sewn_inside = np.array([1, 0, 0, 0, 0, 0, 0, 0], bool)
    panels = np.array([0, 0, 1, 1])
    crossings = crossing_edges(points, triangles)
    where = locate(points, points, elements, rest, limited, inside, sewn_inside, triangles, crossings, panels,
                   ["left", "right"])
    assert where["inside"] == {"panels": ["right", "left"], "stage": "draping"}
    where = locate(points, points, elements, rest, limited, inside, inside, triangles, crossings, panels,
                   ["left", "right"])
    assert where["inside"]["stage"] == "sewing"


def test_cloth_crossing_cloth_names_the_panels_that_cross():
    sewn, triangles, elements, rest, limited = two_squares(gap=-0.5)  # overlapping, but in one plane: no crossing
    draped = sewn.copy()
    draped[[4, 7], 2] = -0.3  # the right square tilted through the left one
    draped[[5, 6], 2] = 0.3
    none = np.zeros(len(sewn), bool)
    args = (elements, rest, limited, none, none, triangles, crossing_edges(draped, triangles), np.array([0, 0, 1, 1]),
            ["left", "right"])
    where = locate(draped, sewn, *args)
    assert sorted(where["crossings"]["panels"]) == ["left", "right"]
    assert where["crossings"]["stage"] == "draping"
