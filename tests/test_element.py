"""One element of the net (section 5): spring period, damper decay, plastic limit."""

import math

import numpy as np
import pytest

from party.model import ModelBuilder
from party.solvers import SolverExplicit
from party.solvers.limit_worklists import EPOCH_LIMIT
from conftest import simulate


def one_element(k: float, c: float, m: float, stretch: float, strain_limit: float = math.inf):
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    anchor = b.add_node((0.0, 0.0, 0.0), 1.0)
    mover = b.add_node((0.1 + stretch, 0.0, 0.0), m)
    b.add_element(anchor, mover, stiffness=k, damping=c, rest_length=0.1, strain_limit=strain_limit)
    b.pin([anchor])
    model = b.finalize("cpu")
    return model, SolverExplicit(model, collision=None)


def trace(model, solver, steps, dt):
    xs = []
    simulate(model, solver, steps, dt, every=1, callback=lambda s, k: xs.append(s.node_q.numpy()[1, 0] - 0.1))
    return np.array(xs)


def test_period_matches_2pi_sqrt_m_over_k():
    k, m, dt = 50.0, 0.02, 1.0e-4
    model, solver = one_element(k, 0.0, m, 0.01)
    x = trace(model, solver, 6000, dt)
    up = np.where((x[:-1] < 0) & (x[1:] >= 0))[0]
    # sub-step crossing times by linear interpolation
    times = (up + (-x[up]) / (x[up + 1] - x[up]) + 1) * dt
    period = np.diff(times).mean()
    expected = 2 * math.pi * math.sqrt(m / k)
    assert abs(period - expected) / expected < 0.01
    assert abs(x.max() - 0.01) / 0.01 < 0.01  # undamped: amplitude kept


def test_damping_decays_as_predicted():
    k, m, c, dt = 50.0, 0.02, 0.02, 1.0e-4
    model, solver = one_element(k, c, m, 0.01)
    x = trace(model, solver, 6000, dt)
    up = np.where((x[:-1] < 0) & (x[1:] >= 0))[0]
    peaks = np.array([x[a:b].max() for a, b in zip(up[:-1], up[1:])])
    ratio = peaks[1:4] / peaks[0:3]
    zeta = c / (2 * math.sqrt(k * m))
    period_d = 2 * math.pi / (math.sqrt(k / m) * math.sqrt(1 - zeta**2))
    expected = math.exp(-c / (2 * m) * period_d)
    assert np.allclose(ratio, expected, rtol=0.01)


def hanging_chain(strain_limit: float):
    """A 10-node chain pinned at the top whose own weight would stretch its top element by
    35 %, far beyond the plastic limit."""
    b = ModelBuilder()
    n, l0, k = 10, 0.05, 50.0
    nodes = [b.add_node((0.0, 0.0, -i * l0), 0.01) for i in range(n)]
    for i in range(n - 1):
        b.add_element(nodes[i], nodes[i + 1], stiffness=k, damping=0.02, rest_length=l0, strain_limit=strain_limit)
    b.pin([nodes[0]])
    model = b.finalize("cpu")
    return model, SolverExplicit(model, collision=None)


def chain_max_ratio(model, solver):
    ratios = []

    def check(state, _):
        p = state.node_q.numpy()
        ratios.append((np.linalg.norm(np.diff(p, axis=0), axis=1) / 0.05).max())

    simulate(model, solver, 4000, 1.0e-4, every=20, callback=check)
    return max(ratios)


def test_plastic_limit_holds_under_load():
    model, solver = hanging_chain(0.0995)
    assert chain_max_ratio(model, solver) <= 1.0995 + 1e-4


def test_without_limit_the_same_load_overstretches():
    model, solver = hanging_chain(math.inf)
    assert chain_max_ratio(model, solver) > 1.3


def test_critical_time_step_scales_with_spacing():
    """dt_crit = 2 / omega_max: omega_max = 2 sqrt(k/m) for an interior chain of the net
    (k = K, m = rho h^2), a little higher at its half-mass edges; so dt_crit is proportional
    to the spacing h and close to 1 / sqrt(K / (rho h^2)) (undamped)."""
    from party.fabric import wool_flannel
    from party.meshing import rectangular_net

    found = {}
    for spacing in (0.02, 0.01):
        net = rectangular_net(0.4, 0.4, spacing)
        b = ModelBuilder()
        b.add_cloth(net, wool_flannel().with_(damping=0.0), np.c_[net.uv, np.zeros(net.node_count)])
        found[spacing] = SolverExplicit(b.finalize("cpu"), collision=None).critical_time_step()
        k, m = wool_flannel().tensile_warp, wool_flannel().areal_density * spacing**2
        assert 0.9 < found[spacing] * math.sqrt(k / m) <= 1.0
    assert found[0.02] / found[0.01] == pytest.approx(2.0, rel=0.02)


def test_critical_time_step_is_the_same_every_time():
    """On a net too large for a dense eigenvalue solve (sparse, iterative), the stable step is
    reproducible to the last bit, so that a run gives the same result every time."""
    from party.fabric import wool_flannel
    from party.meshing import rectangular_net

    net = rectangular_net(0.4, 0.4, 0.02)
    b = ModelBuilder()
    b.add_cloth(net, wool_flannel(), np.c_[net.uv, np.zeros(net.node_count)])
    model = b.finalize("cpu")
    assert 3 * model.node_count > 600
    steps = {SolverExplicit(model, collision=None).critical_time_step() for _ in range(4)}
    assert len(steps) == 1


@pytest.mark.parametrize("c", [0.0, 2.0e3])
def test_critical_time_step_with_damping_is_the_stability_edge(c):
    """One free node on a spring-damper to a pin: bounded at 0.99 dt_crit (near the edge the
    undamped speed may swing up to 1 / sqrt(1 - 0.99^2) = 7 times its start), growing without
    bound at 1.02 dt_crit."""
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    pin = b.add_node((0.0, 0.0, 0.0), 1.0)
    node = b.add_node((0.1, 0.0, 0.0), 1.0)
    b.add_element(pin, node, stiffness=1.0e6, damping=c, rest_length=0.1)
    b.pin([pin])
    model = b.finalize("cpu")
    solver = SolverExplicit(model, collision=None)
    dt_crit = solver.critical_time_step()
    w2 = 1.0e6
    assert dt_crit == pytest.approx((math.sqrt(c * c + 4 * w2) - c) / w2, rel=1e-6)
    for factor, grows in ((0.99, False), (1.02, True)):
        state = model.state(velocity=(1.0, 0.0, 0.0))
        scratch = model.state()
        for _ in range(3000):
            solver.step(state, scratch, model.control(), factor * dt_crit)
            state, scratch = scratch, state
        assert (not np.abs(state.velocities()[1]).max() < 100.0) == grows  # NaN counts as grown


def test_plastic_sweep_in_one_cpu_launch_is_the_sweep_colour_by_colour():
    """On the CPU a plastic-limit sweep is one launch over all colours in order; it must give
    the velocities, to the bit, of one launch per colour, and leave no element beyond its limit
    at the end of the step."""
    from party.fabric import wool_flannel
    from party.meshing import rectangular_net
    from party.solvers.plastic_limit import TOLERANCE as PLASTIC_TOLERANCE
    from party.solvers.plastic_limit import PlasticLimit

    net = rectangular_net(0.2, 0.2, 0.02)
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    b.add_cloth(net, wool_flannel(), np.c_[net.uv, np.zeros(net.node_count)])
    model = b.finalize("cpu")
    assert len(model.element_color_offsets) > 3
    pull = np.random.default_rng(1).normal(0.0, 30.0, (model.node_count, 3))
    dt = 1e-3
    found = []
    for serial in (True, False):
        limit = PlasticLimit(model, 200, serial=serial)
        state = model.state()
        state.node_qd.assign(pull.astype(np.float32))
        limit.apply(state, dt)
        found.append(state.velocities())
    assert np.array_equal(found[0], found[1])
    x = model.host.points + found[0] * dt
    e = model.host.elements
    length = np.linalg.norm(x[e[:, 1]] - x[e[:, 0]], axis=1)
    limit = model.element_max_length.numpy()
    assert np.all(length <= limit * (1.0 + 2 * PLASTIC_TOLERANCE))


def pulled_sheet_sweeps(serial: bool, seed: int, epoch: int | None = None):
    """A 20 cm wool sheet pinned at a corner, its nodes pulled at random (30 m/s) twice;
    returns the first pull and a function giving, for an over-relaxation, the sweeps taken,
    the velocities and the nodes each correction moved (``moved_in``) of two plastic limits,
    one after each pull, by one PlasticLimit (so the second starts where the first left its
    bookkeeping), on the CPU in one launch (``serial``; the second limit's worklists counting
    their sweeps on from ``epoch`` where given) or one launch per colour."""
    from party.fabric import wool_flannel
    from party.meshing import rectangular_net
    from party.solvers.plastic_limit import PlasticLimit

    net = rectangular_net(0.2, 0.2, 0.02)
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    b.add_cloth(net, wool_flannel(), np.c_[net.uv, np.zeros(net.node_count)])
    b.pin([0])
    model = b.finalize("cpu")
    pulls = np.random.default_rng(seed).normal(0.0, 30.0, (2, model.node_count, 3)).astype(np.float32)

    def sweep(over_relaxation: float, skip_unchanged: bool = True) -> tuple[list[int], np.ndarray, np.ndarray]:
        limit = PlasticLimit(model, 200, serial=serial, skip_unchanged=skip_unchanged)
        state = model.state()
        sweeps, velocities, moved = [], [], []
        for k, pull in enumerate(pulls):
            if k == 1 and epoch is not None:
                limit.worklists.epoch.fill_(epoch)
            state.node_qd.assign(pull)
            sweeps.append(limit.apply(state, 1e-3, over_relaxation))
            velocities.append(state.velocities())
            moved.append(limit.moved.numpy() > 0)
        return sweeps, np.array(velocities), np.array(moved)

    return pulls[0], sweep


@pytest.mark.parametrize("serial, epoch", [(True, None), (True, int(EPOCH_LIMIT) + 1), (False, None)])
def test_plastic_sweeps_leaving_out_unchanged_elements_end_bit_for_bit_as_full_sweeps(serial, epoch):
    """Sweeps after the first leave out elements whose nodes no correction has changed since
    the last sweep began (on the CPU visiting only the elements queued for them, also where
    the second limit starts their marks again); over a randomly pulled sheet, pulled twice, at
    both over-relaxations, they must give the velocities and moved nodes of sweeps over every
    element to the bit, in as many sweeps."""
    from party.solvers.plastic_limit import OVER_RELAXATION

    pull, sweep = pulled_sheet_sweeps(serial, seed=2, epoch=epoch)
    for over_relaxation in (1.0, OVER_RELAXATION):
        sweeps, skipping, moved = sweep(over_relaxation)
        full_sweeps, full, full_moved = sweep(over_relaxation, skip_unchanged=False)
        assert sweeps == full_sweeps and min(sweeps) > 3
        assert np.array_equal(skipping, full) and np.array_equal(moved, full_moved)
        assert not np.array_equal(full[0], pull)


def test_plastic_sweeps_in_one_launch_end_bit_for_bit_as_sweeps_launched_by_colour():
    """On the CPU all of a plastic limit's sweeps run in one single-thread launch; over a
    randomly pulled sheet, pulled twice, at both over-relaxations, that gives the velocities
    and moved nodes of one launch per colour with a read of the count after each sweep, to
    the bit, in as many sweeps."""
    from party.solvers.plastic_limit import OVER_RELAXATION as PLASTIC_OVER_RELAXATION

    (pull, in_one_launch), (_, by_colour) = pulled_sheet_sweeps(True, seed=3), pulled_sheet_sweeps(False, seed=3)
    for over_relaxation in (1.0, PLASTIC_OVER_RELAXATION):
        one_launch_sweeps, fused, fused_moved = in_one_launch(over_relaxation)
        colour_sweeps, launched, launched_moved = by_colour(over_relaxation)
        assert one_launch_sweeps == colour_sweeps and min(one_launch_sweeps) > 3
        assert np.array_equal(fused, launched) and np.array_equal(fused_moved, launched_moved)
        assert not np.array_equal(fused[0], pull)


def test_elements_placed_beyond_their_limit_yield_to_the_placement():
    """A chain placed with its second element at 1.5 times rest (limit 1.1): that element's
    limit becomes its placed length and the others keep rest x 1.1; once yielded, nothing
    is left to yield."""
    b = ModelBuilder()
    x = [0.0, 0.01, 0.025, 0.035]
    nodes = [b.add_node((xi, 0.0, 0.0), 1e-3) for xi in x]
    for i, k in zip(nodes, nodes[1:]):
        b.add_element(i, k, stiffness=50.0, rest_length=0.01, strain_limit=0.1)
    assert b.yield_to_placement() == (1, pytest.approx(1.5))
    model = b.finalize("cpu")
    assert model.element_max_length.numpy() == pytest.approx([0.011, 0.015, 0.011])
    assert b.yield_to_placement() == (0, 1.0)


def test_over_relaxed_plastic_sweeps_converge_faster_to_the_same_bound():
    """A column of 40 elements, hung from a pinned top node at its limit, each node falling
    faster than the one above it: every element would end the step beyond its limit. The
    paper's f_plas (over-relaxation 1) spreads the corrections one element per sweep; over-
    relaxed at PLASTIC_OVER_RELAXATION it reaches the same tolerance in under half the sweeps.
    Both leave no element beyond its limit, and over-relaxation leaves none shorter than its
    rest length (it overshoots, never reverses the stretch)."""
    from party.solvers.plastic_limit import OVER_RELAXATION as PLASTIC_OVER_RELAXATION
    from party.solvers.plastic_limit import TOLERANCE as PLASTIC_TOLERANCE
    from party.solvers.plastic_limit import PlasticLimit

    l0, strain_limit, n = 0.02, 0.1, 41
    b = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    nodes = [b.add_node((0.0, 0.0, -i * l0 * (1 + strain_limit)), 0.01) for i in range(n)]
    for i in range(n - 1):
        b.add_element(nodes[i], nodes[i + 1], stiffness=50.0, rest_length=l0, strain_limit=strain_limit)
    b.pin([nodes[0]])
    model = b.finalize("cpu")
    dt = 1.0 / 300.0
    falling = np.zeros((n, 3), np.float32)
    falling[:, 2] = -0.3 * np.arange(n) / n
    sweeps, lengths = {}, {}
    for over_relaxation in (1.0, PLASTIC_OVER_RELAXATION):
        limit = PlasticLimit(model, 5000)
        state = model.state()
        state.node_qd.assign(falling)
        sweeps[over_relaxation] = limit.apply(state, dt, over_relaxation)
        x = model.host.points + state.velocities() * dt
        lengths[over_relaxation] = np.linalg.norm(np.diff(x, axis=0), axis=1)
    for found in lengths.values():
        assert found.max() <= l0 * (1 + strain_limit) * (1 + 2 * PLASTIC_TOLERANCE)
        assert found.min() >= l0
    assert sweeps[PLASTIC_OVER_RELAXATION] < sweeps[1.0] / 2


def test_plastic_over_relaxation_outside_one_to_two_is_refused():
    from party.errors import InvalidInput
    from party.solvers.filters import StepFilters

    model, _ = hanging_chain(0.1)
    with pytest.raises(InvalidInput, match=r"plastic over-relaxation must be in \[1, 2\), got 2.0"):
        StepFilters(model, None, plastic_passes=8, plastic_over_relaxation=2.0)


def test_elements_beyond_limit_counts_what_the_limit_has_not_taken_back():
    """An element counts once it is more than 2 % longer than its plastic limit (which, for a
    sewn garment, is its sewn length where that was longer); an element without a limit never."""
    from party.output.metrics import elements_beyond_limit

    points = np.array([[0, 0, 0], [1.03, 0, 0], [0, 1.01, 0], [0, 0, 10.0]], float)
    elements = np.array([[0, 1], [0, 2], [0, 3]])
    assert elements_beyond_limit(points, elements, np.array([1.0, 1.0, np.inf])) == 1
    assert elements_beyond_limit(points, elements, np.array([1.0, 1.0, np.inf]), tolerance=0.005) == 2
    assert elements_beyond_limit(points, elements, np.array([1.02, 1.0, 9.0])) == 1
