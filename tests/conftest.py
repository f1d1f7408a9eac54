import os
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from party import device, launch
from party.solvers.registry import SOLVERS

if os.environ.get("PYTEST_XDIST_WORKER") and "PARTY_THREADS" not in os.environ:
    # pytest-xdist runs a test process per core: each keeps to its share of the cores, since
    # the implicit solver's workers spin at barriers (docs/design.md, Kernels and CPU threads)
    os.environ["PARTY_THREADS"] = str(max(1, launch.CORES // int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))))


@pytest.fixture(params=sorted(SOLVERS))
def solver_name(request) -> str:
    """Each registered solver by name, in turn: a physics test that takes ``solver_name`` holds
    for every solver ``--solver`` offers, a new one included."""
    return request.param


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


def wait_for_file(path: Path, running: subprocess.Popen, seconds: float = 300.0) -> None:
    """Wait until ``path`` exists, ``running`` has ended or ``seconds`` have passed."""
    deadline = time.monotonic() + seconds
    while not path.exists() and running.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)


@pytest.fixture
def rng():
    return np.random.default_rng(7)
