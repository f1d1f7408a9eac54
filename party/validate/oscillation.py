"""Case 1: oscillation periods against their analytic values.

A mass on a spring: T = 2 pi sqrt(m / k). A cloth strip held at one end and stretched along
its warp in its first mode, free of gravity and dampers: a fixed-free elastic bar, whose
first period is T = 4 L / c with c = sqrt(tensile stiffness / areal density).
"""

from __future__ import annotations

import math

import numpy as np

from ..fabric import Fabric
from ..meshing import rectangular_net
from ..model import ModelBuilder
from ..solvers.registry import solver_class
from .checks import CaseResult, Check
from .simulate import run

NAME = "oscillation"
TOLERANCE = 0.01  # relative period error
SPRING_PERIOD = 0.5  # s
STRIP_LENGTH, STRIP_WIDTH = 0.3, 0.02  # m
STRIP_STRAIN = 0.005  # peak strain of the initial mode shape


def run_case(fabric: Fabric, solver: str, *, quick: bool = False, out=None) -> CaseResult:
    result = CaseResult(NAME)
    period, reference = spring_mass_period(solver)
    result.checks.append(Check.relative(NAME, "spring-mass period [s]", period, reference, TOLERANCE))
    period, reference = strip_period(fabric, solver, spacing=0.02 if quick else 0.01)
    result.checks.append(Check.relative(NAME, f"{fabric.name} strip period, first mode [s]", period, reference, TOLERANCE))
    return result


def spring_mass_period(solver: str) -> tuple[float, float]:
    """Simulated and analytic period [s] of 10 g on a spring, free of gravity."""
    mass, rest, amplitude = 0.01, 0.1, 0.01
    stiffness = 4.0 * math.pi**2 * mass / SPRING_PERIOD**2
    builder = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    anchor = builder.add_node((0.0, 0.0, 0.0), mass)
    bob = builder.add_node((rest + amplitude, 0.0, 0.0), mass)
    builder.pin([anchor])
    builder.add_element(anchor, bob, stiffness=stiffness, rest_length=rest)
    model = builder.finalize()
    return _period(model, solver, bob, SPRING_PERIOD, axis=0, offset=rest), SPRING_PERIOD


def strip_period(fabric: Fabric, solver: str, *, spacing: float) -> tuple[float, float]:
    """Simulated and analytic first period [s] of a strip (warp along its length) held at one
    end, without gravity and dampers, set moving in its first mode u = A sin(pi x / 2 L)."""
    fabric = fabric.with_(damping=0.0)
    net = rectangular_net(STRIP_LENGTH, STRIP_WIDTH, spacing)
    u = net.uv[:, 0]
    amplitude = STRIP_STRAIN * 2.0 * STRIP_LENGTH / math.pi
    points = np.c_[u + amplitude * np.sin(0.5 * math.pi * u / STRIP_LENGTH), net.uv[:, 1], np.zeros(net.node_count)]
    builder = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    builder.add_cloth(net, fabric, points)
    builder.pin(np.flatnonzero(u < 1e-9))
    model = builder.finalize()
    wave_speed = math.sqrt(fabric.tensile_warp / fabric.areal_density)
    reference = 4.0 * STRIP_LENGTH / wave_speed
    tip = np.flatnonzero(u > STRIP_LENGTH - 1e-9)
    return _period(model, solver, tip, reference, axis=0, offset=STRIP_LENGTH), reference


def _period(model, solver: str, nodes, expected: float, *, axis: int, offset: float) -> float:
    """Mean time [s] between upward zero crossings of the nodes' mean displacement, over three
    expected periods."""
    dt = solver_class(solver).dynamics_step(model, resolve_period=expected)
    nodes = np.atleast_1d(nodes)
    trace = []
    run(model, solver, 3.2 * expected, dt=dt, collision=None,
        observe=lambda s: trace.append(float(s.node_q.numpy()[nodes, axis].mean()) - offset))
    x = np.asarray(trace)
    t = dt * np.arange(1, len(x) + 1)
    up = np.flatnonzero((x[:-1] < 0.0) & (x[1:] >= 0.0))
    crossings = t[up] - x[up] * dt / (x[up + 1] - x[up])
    if len(crossings) < 2:
        return math.nan
    return float(np.mean(np.diff(crossings)))
