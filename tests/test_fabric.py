"""Table 1's conversion gives a plausible wool flannel."""

import numpy as np
import pytest

from party.errors import InvalidInput
from party.fabric import wool_flannel
from party.meshing import rectangular_net
from party.model import ModelBuilder
from party.solvers import SolverExplicit
from conftest import simulate


def test_table1_in_si():
    f = wool_flannel()
    assert f.areal_density == pytest.approx(0.23)
    assert f.tensile_warp == pytest.approx(980.665)
    assert f.tensile_weft == pytest.approx(902.2118)
    assert f.damping == pytest.approx(40.0)
    assert (f.strain_limit, f.friction, f.restitution) == (0.0995, 0.6, 0.03)
    assert (f.momentum_propagation, f.cloth_friction) == (0.5, 0.23)


def test_hanging_strip_stretches_as_its_weight_predicts():
    """A 1 m strip hanging from its top edge: strain at height s is rho g (L - s) / K, so its
    length grows by rho g L^2 / (2 K) = 1.15 mm for wool flannel along the warp."""
    f = wool_flannel().with_(damping=400.0)
    net = rectangular_net(1.0, 0.1, 0.025)  # u (warp) vertical
    pts = np.c_[np.zeros(net.node_count), net.uv[:, 1], -net.uv[:, 0]]
    b = ModelBuilder()
    cloth = b.add_cloth(net, f, pts)
    b.pin(cloth.nodes(np.where(net.uv[:, 0] == 0.0)[0]))
    model = b.finalize("cpu")
    state = simulate(model, SolverExplicit(model, collision=None), 20000, 1e-4)
    z = state.positions()[:, 2]
    stretch = -z.min() - 1.0
    expected = f.areal_density * 9.80665 * 1.0**2 / (2 * f.tensile_warp)
    assert stretch == pytest.approx(expected, rel=0.05)
    assert expected == pytest.approx(1.15e-3, rel=0.01)


@pytest.mark.parametrize("field,value,message", [
    ("areal_density", -0.1, "areal_density must be positive"),
    ("areal_density", 0.0, "areal_density must be positive"),
    ("tensile_warp", 0.0, "tensile_warp must be positive"),
    ("tensile_weft", float("nan"), "tensile_weft must be positive"),
    ("friction", -1.0, "friction must be non-negative"),
    ("momentum_propagation", 1.5, "momentum_propagation must lie in [0, 1]"),
])
def test_bad_fabric_parameters(field, value, message):
    with pytest.raises(InvalidInput, match=message.replace("[", r"\[").replace("]", r"\]")):
        wool_flannel().with_(**{field: value})
