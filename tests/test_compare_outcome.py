"""The benchmark's outcome checks, measured as every system's are (benchmarks/compare.py)."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from compare import LAST_INTERVAL, SPHERE_RADIUS, party_sphere  # noqa: E402

from party.solvers.registry import solver_class  # noqa: E402
from party.units import GRAVITY  # noqa: E402


def test_the_final_speed_of_a_sheet_still_in_free_fall_is_implicit_eulers():
    """0.2 s into the drop the sheet has not reached the sphere (it falls 0.2 m of its 0.32). By
    implicit Euler from rest, v_n = n g dt and x_n = x_{n-1} + v_n dt, so over the last k of N
    steps the nodes move g dt^2 (k N - k (k - 1) / 2): a mean speed of g dt (N - (k - 1) / 2)."""
    dt = solver_class("implicit").default_dt
    row = party_sphere("implicit", 8, False, 0.2, None, "cpu")
    steps, last = round(0.2 / dt), round(LAST_INTERVAL / dt)
    assert row["nodes_inside"] == 0 and row["z_min_m"] > SPHERE_RADIUS
    assert row["speed_mean_m_s"] == pytest.approx(GRAVITY * dt * (steps - (last - 1) / 2), rel=1e-4)
