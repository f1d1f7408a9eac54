import numpy as np
import pytest

from party import device


@pytest.fixture(scope="session", autouse=True)
def _quiet_warp():
    device.init()


def simulate(model, solver, steps: int, dt: float, control=None, every: int = 0, callback=None):
    """Step a model; optionally call ``callback(state, step)`` every ``every`` steps."""
    state, scratch = model.state(), model.state()
    control = control or model.control()
    for k in range(steps):
        solver.step(state, scratch, control, dt)
        state, scratch = scratch, state
        if every and (k + 1) % every == 0:
            callback(state, k + 1)
    return state


@pytest.fixture
def rng():
    return np.random.default_rng(7)
