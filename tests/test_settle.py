"""Static equilibrium by damped dynamics (party.solvers.settle)."""

import numpy as np
import pytest

from party.model import ModelBuilder
from party.solvers.settle import SettleSettings, settle

G = 9.80665


def hanging_mass(k: float = 50.0, m: float = 0.02):
    b = ModelBuilder()
    pin = b.add_node((0.0, 0.0, 0.0), 1.0)
    bob = b.add_node((0.0, 0.0, -0.1), m)
    b.add_element(pin, bob, stiffness=k, damping=0.0, rest_length=0.1)
    b.pin([pin])
    return b.finalize("cpu")


def test_settled_spring_hangs_at_its_static_stretch(solver_name):
    """A mass on a spring comes to rest at l0 + m g / k below its pin (within the rest
    criterion's creep), whatever the solver."""
    k, m = 50.0, 0.02
    settled = settle(hanging_mass(k, m), solver_name, SettleSettings(collision=None, rest_speed=1e-5))
    assert settled.at_rest
    z = settled.state.positions()[1, 2]
    assert z == pytest.approx(-(0.1 + m * G / k), abs=2e-5)


def test_settle_says_when_the_time_ran_out():
    settled = settle(hanging_mass(), "explicit", SettleSettings(collision=None, max_seconds=0.02))
    assert not settled.at_rest
    assert settled.seconds == pytest.approx(0.02, rel=0.01)
    assert np.all(np.isfinite(settled.state.positions()))
