"""Panel meshing: grain alignment, outline coverage, seam node counts."""

import numpy as np
import pytest

from party.garment.assemble import assemble
from party.meshing.net import ElementKind
from party.meshing.panel_mesh import mesh_panel
from party.pattern import EdgeRef, Panel, Pattern, Seam, arc_through_radius, bezier, line


def blob(name="p", grain=(1.0, 0.0), scale=1.0):
    a, b, c, d = np.array([[0, 0], [0.4, 0], [0.45, 0.3], [0.0, 0.35]]) * scale
    edges = (line(a, b), bezier(b, [[0.5 * scale, 0.15 * scale]], c),
             arc_through_radius(c, d, 0.4 * scale, large_arc=False, ccw=True), line(d, a))
    return Panel(name, edges, np.array(grain))


@pytest.mark.parametrize("angle", [0.0, 30.0, 90.0])
def test_warp_and_weft_lie_along_the_grain(angle):
    grain = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
    mesh = mesh_panel(blob(grain=grain), 0.02)
    net = mesh.net
    e = net.elements[net.element_warp_share() == 1.0]
    d = mesh.xy[e[:, 1]] - mesh.xy[e[:, 0]]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    assert len(e) > 100
    assert np.degrees(np.arccos(np.clip(np.abs(d @ grain), 0, 1))).max() < 1.0
    assert mesh.quality["grain_error_deg"] < 1.0


def test_triangles_cover_the_outline_and_keep_shape():
    panel = blob()
    mesh = mesh_panel(panel, 0.015)
    assert mesh.net.rest_triangle_areas().sum() == pytest.approx(panel.polygon().area, rel=0.01)
    assert mesh.quality["min_angle_deg"] > 15.0
    assert set(np.unique(mesh.net.kinds)) <= {ElementKind.WARP, ElementKind.WEFT, ElementKind.SHEAR}


def test_both_sides_of_a_seam_get_the_same_node_count():
    short = blob("short", scale=0.8)
    long_ = blob("long", scale=1.0)
    pattern = Pattern("two", {"short": short, "long": long_}, (Seam(EdgeRef("short", 3), EdgeRef("long", 3)),
                                                              Seam(EdgeRef("short", 1), EdgeRef("long", 1))))
    g = assemble(pattern, 0.02)
    for k, edge in ((0, 3), (1, 1)):
        a, b = g.panels[0].edge_nodes[edge], g.panels[1].edge_nodes[edge]
        assert len(a) == len(b) == np.sum(g.seam_of_pair == k)
        assert len(a) - 1 == round(pattern.edge(EdgeRef("long", edge)).length() / 0.02)
    net, node_map = g.sewn()
    assert net.node_count == g.node_count - len(g.seam_pairs)


def test_thread_ends_put_free_edge_nodes_where_threads_cross_so_bending_reaches_the_edge():
    """With ``thread_ends`` every node along a free edge (bar the edges' corners) lies on a
    thread of the grid, so threads run straight to the edge and the last grid node before it
    carries a bending stencil: under half as many inner nodes lack one as with even spacing."""
    from party.meshing.hinges import hinges
    from party.validate.cusick import specimen_panel

    def lacking(mesh):
        nodes, weights, _ = hinges(mesh.net)
        centres = np.bincount(nodes[weights[:, 3] == 0, 1], minlength=mesh.net.node_count)
        ring = np.zeros(mesh.net.node_count, bool)
        ring[np.concatenate(mesh.edge_nodes)] = True
        return np.sum((centres < 2) & ~ring)

    spacing = 0.0075
    even = mesh_panel(specimen_panel(0.127), spacing)
    ends = mesh_panel(specimen_panel(0.127), spacing, thread_ends=True)
    grid = ends.net.uv[len(np.concatenate([e[:-1] for e in ends.edge_nodes])):]
    offset = grid[0]
    for edge in ends.edge_nodes:
        phase = (ends.net.uv[edge[1:-1]] - offset) / spacing
        assert np.all(np.min(np.abs(phase - np.round(phase)), axis=1) < 1e-9)
    assert lacking(ends) < 0.5 * lacking(even)
    assert ends.net.rest_triangle_areas().sum() == pytest.approx(np.pi * 0.127**2, rel=0.01)
