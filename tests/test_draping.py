"""The explicit drape (party.garment.draping.KineticDrape): cloth sewn out level falls to hang
within the drape's iterations, and stops there."""

import numpy as np

from party.fabric import wool_flannel
from party.garment.draping import KineticDrape
from party.meshing.net import rectangular_net
from party.model import ModelBuilder
from party.solvers.relax import KINETIC_MOMENTUM

LENGTH = 0.5


def level_strip():
    """A 0.5 m by 0.1 m strip of wool flannel held level by its edge at x = 0, under gravity (-z)."""
    net = rectangular_net(LENGTH, 0.1, 0.02)
    builder = ModelBuilder()
    builder.add_cloth(net, wool_flannel(), np.c_[net.uv, np.zeros(net.node_count)])
    builder.pin(np.flatnonzero(net.uv[:, 0] < 1e-9))
    return builder.finalize("cpu")


def drape(momentum: float):
    model = level_strip()
    state = model.state()
    settled, energy = KineticDrape(momentum=momentum).run(model, state, 0, [], lambda *_: None, False)
    return settled, state.positions()


def test_a_strip_sewn_out_level_falls_to_hang_and_comes_to_rest():
    """Half a metre of cloth held level, as a circle skirt's hem comes out of the sewing, must
    fall to hang down from its edge, its far end nearly a strip's length below (within the
    plastic limit's 10 % of stretch and 5 % of slant), and the drape must say it came to rest."""
    settled, points = drape(KineticDrape().momentum)
    assert settled.at_rest
    assert -(1.0 + wool_flannel().strain_limit) * LENGTH < points[:, 2].min() < -0.95 * LENGTH


def test_the_sewings_damping_would_leave_it_falling():
    """The sewing's kinetic damping (terminal speed a few cm/s) would stop at the iteration cap
    with the strip still on its way: the reason the drape keeps more of the velocity."""
    settled, points = drape(KINETIC_MOMENTUM)
    assert not settled.at_rest and points[:, 2].min() > -0.9 * LENGTH
