"""Pinned nodes stay put; nodes on a moving handle follow it and pull the cloth."""

import numpy as np
import warp as wp

from party.fabric import wool_flannel
from party.meshing import rectangular_net
from party.model import ModelBuilder
from party.solvers import SolverExplicit


def test_handle_drags_a_corner_and_the_cloth_follows():
    net = rectangular_net(0.2, 0.2, 0.02)
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    cloth = b.add_cloth(net, wool_flannel(), np.c_[net.uv, np.zeros(net.node_count)])
    pinned, handle = cloth.nodes([0]), cloth.nodes([net.node_count - 1])
    b.pin(np.concatenate([pinned, handle]))
    model = b.finalize("cpu")
    solver = SolverExplicit(model, collision=None)
    control = model.control()
    pull = np.zeros((model.node_count, 3), np.float32)
    pull[handle] = (0.1, 0.1, 0.0)  # m/s, along the diagonal, away from the pinned corner
    control.kinematic_velocity = wp.array(pull, dtype=wp.vec3, device="cpu")
    state, scratch = model.state(), model.state()
    start = state.positions()
    for _ in range(5000):
        solver.step(state, scratch, control, 1e-4)
        state, scratch = scratch, state
    end = state.positions()
    assert np.allclose(end[pinned], start[pinned])
    assert np.allclose(end[handle] - start[handle], [0.05, 0.05, 0.0], atol=1e-5)
    # the plastic limit caps the stretch: the diagonal is pulled 25 % longer than it can go
    # (9.95 %), so the free nodes must move along with the handle
    middle = net.node_count // 2
    assert end[middle, 0] - start[middle, 0] > 0.01
