"""The implicit solver's contact re-solve: the cloth around a node that Collision() stopped
follows it within the step (:meth:`party.solvers.implicit.SolverImplicit.resolve_contacts`)."""

import numpy as np

from party.collision import CollisionSettings
from party.fabric import wool_flannel
from party.meshing import rectangular_net
from party.model import ModelBuilder
from party.output.metrics import max_elongation
from party.solvers.registry import make_solver

SHEET, SPACING, PATCH = 0.3, 0.02, 0.04
DT = 1.0 / 100.0
SPEED = 3.0  # m/s down: 30 mm a step, one and a half spacings


def sheet_over_patch():
    """A falling sheet whose centre lands, within one step, on a small held patch of cloth."""
    fabric = wool_flannel()
    b = ModelBuilder()
    net = rectangular_net(SHEET, SHEET, SPACING)
    b.add_cloth(net, fabric, np.c_[net.uv - SHEET / 2, np.zeros(net.node_count)], name="sheet")
    patch = rectangular_net(PATCH, PATCH, SPACING)
    below = -2.0 * fabric.thickness - 0.005
    held = b.add_cloth(patch, fabric, np.c_[patch.uv - PATCH / 2, np.full(patch.node_count, below)], name="patch")
    b.pin(held.nodes(np.arange(patch.node_count)))
    model = b.finalize("cpu")
    state = model.state()
    v = state.node_qd.numpy()
    v[: net.node_count] = (0.0, 0.0, -SPEED)
    state.node_qd.assign(v)
    return model, state, net.node_count


def one_step(resolve: bool):
    model, state, sheet_nodes = sheet_over_patch()
    solver = make_solver("implicit", model, collision=CollisionSettings())
    if not resolve:
        solver.filters.contact_resolve = None
    out = model.state()
    solver.step(state, out, model.control(), DT)
    p = out.positions()
    h = model.host
    sheet = np.all(model.elements < sheet_nodes, axis=1) & model.limited_elements
    stretch = max_elongation(p, model.elements[sheet], h.element_rest_length[sheet], np.ones(sheet.sum(), bool))
    over = np.all(np.abs(p[:sheet_nodes, :2]) < PATCH / 2, axis=1)
    return stretch, p[:sheet_nodes, 2], p[:sheet_nodes][over, 2].min()


def test_a_node_stopped_by_another_layer_takes_its_neighbours_with_it_within_the_step():
    """Over a step of 10 ms the sheet's centre meets the patch and stops (eqs. 13-14) while the
    rest falls 30 mm on. Without the re-solve the elements at the patch's rim end the step far
    beyond wool flannel's plastic limit (9.95 %); with it they end within the limit's tolerance
    and the sheet's centre has not passed the patch."""
    limit = 1.0 + wool_flannel().strain_limit
    stretched, _, _ = one_step(resolve=False)
    followed, z, centre = one_step(resolve=True)
    assert stretched > limit + 0.05
    assert followed < limit + 0.01
    assert z.min() < -0.02  # the rest of the sheet fell on
    assert centre > -0.005  # the centre stopped above the patch (5 mm and two thicknesses below its start)


def test_the_gpus_region_and_sweeps_give_the_cpus_result_bit_for_bit():
    """On a GPU the re-solve's region is found ring by ring, a thread per node, and its sweeps run
    over every node (those outside the region held); on the CPU one thread searches and the
    sweeps visit the region alone. Run on the CPU both ways, the step ends the same to the bit."""
    ends = []
    for serial in (True, False):
        model, state, _ = sheet_over_patch()
        solver = make_solver("implicit", model, collision=CollisionSettings())
        solver.serial_region = serial
        out = model.state()
        solver.step(state, out, model.control(), DT)
        ends.append((out.positions(), out.velocities()))
    assert np.array_equal(ends[0][0], ends[1][0]) and np.array_equal(ends[0][1], ends[1][1])
