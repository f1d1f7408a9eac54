"""Sewing a garment onto a body: the panels placed round it, pulled together by sewing springs,
closed, joined into one net and settled, all by static relaxation (the paper's iteration
ignoring inertia, section 7) with the paper's explicit steps.

Cloth-cloth collision waits for the merge: while springs pull the panels together, panels that
meet at an armpit (front, back and two sleeve halves) would collide with one another short of
their partners and keep seams open. A crossing made while sewing would stay in the garment, since
collision response keeps each node on the side of a layer it is on, so the joined garment's
crossings are undone (:func:`party.collision.untangle.untangle`) before it settles with
cloth-cloth collision on, and once more after.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from ..body.body import Body
from ..collision import presets
from ..collision.untangle import untangle
from ..errors import SimulationUnstable
from ..fabric import Fabric
from ..meshing.net import ClothNet
from ..model import Model, ModelBuilder
from ..progress import relax_progress
from ..solvers.explicit import SolverExplicit
from ..solvers.relax import KINETIC_MOMENTUM, RelaxResult, StaticRelaxation
from .assemble import Garment
from .body_parts import garment_ignored_parts, sewn_ignored_parts
from .dressing import dress
from .worn import garment_model


@dataclass(frozen=True)
class SewingSettings:
    """How a garment is sewn (:func:`sew`).

    Attributes:
        max_iterations: Iterations of the first stage's round (the closing and each settling
            round take a quarter, at least 200).
        rounds: Most rounds of the first stage while a seam is still more than ``open_gap``
            apart [m] and its energy has not settled: stiff fabrics take smaller explicit steps
            and so need more of them to close.
        open_gap: See ``rounds`` [m].
        closed_gap: Largest distance [m] between paired seam nodes that the closing allows: the
            sewing springs get a plastic limit of this length, which pulls the last millimetres
            shut as a constraint where the cloth pulls against the springs.
        seam_rest_length: Rest length of a sewing spring [m] (zero in effect; a spring needs a
            direction).
        seam_stiffness: Sewing spring constant as a multiple of the fabric's median element
            constant: stiff enough to close seams to well under a millimetre against the
            cloth's pull. It sets the first stage's stable step.
        momentum: Velocity kept per iteration of the first stage (kinetic damping).
        sewing_speed: Speed cap [m/s] of the first stage, whose panels travel far.
        settling_speed: Speed cap [m/s] of the closing and the settling: no node moves beyond
            the collision search in one iteration.
        settling_limit: The plastic limit [-] of the spreading, the settling's first phase (the
            fabric's own limit where that is larger): a pattern smaller than its wearer, such
            as a tall waistband sized to the waist whose lower edge reaches the hips, must
            stretch by the difference, 20 % and more, and at the fabric's limit (10 % for most)
            no shape satisfies it: the limit and the body push against each other and gather
            the stretch in the few elements at the body's most curved points. Just below the
            quality gate's 1.3 times rest, the stretch such a pattern needs is spread round it.
            The settling at the fabric's limit follows, and its result is kept unless it leaves
            an element beyond ``spread_beyond`` times rest, more than the spreading did: a
            garment that fits keeps the paper's limit. Off (0: the fabric's limit only) by
            default: GarmentCode's jumpsuit, spread, drapes with its sleeves pulled to five
            times rest; 0.25 is the value to study.
        spread_beyond: See ``settling_limit`` [-]: the quality gate's largest stretch; the
            spreading's rounds also go on while elements stay beyond it.
        exchange: The settling's cloth-cloth exchange (gamma, kappa of eqs. 13-14): with both 1 a
            contact only stops the approach along its normal and leaves the sliding as it was,
            as the sewing leaves out skin friction; the fabric's own would cut a node's whole
            velocity in contact, and with it what the plastic limit asks of it.
        settling_rounds: Most rounds of the settling (the joined garment under its plastic
            limit): they go on while elements are stretched beyond ``overstretched`` times rest
            and each round cuts the elements' total length beyond their limits by at least
            ``settling_progress`` of what it was. The first stage, which has no plastic limit,
            can leave a panel stretched where seams pulled it faster than it could slide; a
            pattern smaller than its wearer stays stretched however long it settles, and stops
            once a round shows it. Progress is the excess, not the count of stretched
            elements: as the limit pulls a panel back, its stretch gathers in the few elements
            the body holds out, whose count may rise for a round while the whole falls.
        overstretched: See ``settling_rounds`` [-].
        settling_progress: See ``settling_rounds`` [-].
    """

    max_iterations: int = 6000
    rounds: int = 4
    open_gap: float = 0.01
    closed_gap: float = 5.0e-4
    seam_rest_length: float = 1.0e-4
    seam_stiffness: float = 4.0
    momentum: float = KINETIC_MOMENTUM
    sewing_speed: float = 4.0
    settling_speed: float = 1.0
    settling_limit: float = 0.0
    spread_beyond: float = 1.3
    exchange: tuple[float, float] = (1.0, 1.0)
    settling_rounds: int = 10
    overstretched: float = 1.5
    settling_progress: float = 0.05

    @property
    def stage_iterations(self) -> int:
        """Iterations of the closing and of each settling round."""
        return max(self.max_iterations // 4, 200)


@dataclass
class Sewn:
    """A garment after sewing.

    Attributes:
        garment: The meshed pattern.
        net: The sewn net (seam nodes merged).
        node_map: Garment node -> sewn node.
        points: Sewn node positions [m].
        seam_gaps: Per pattern seam, the largest distance [m] between its paired nodes when
            they were merged.
        relaxation: The sewing relaxation's log (panels and sewing springs).
        settling: The log of the joined garment's relaxation that follows (plastic limit on).
        dt: Pseudo time step of the relaxation [s].
    """

    garment: Garment
    net: ClothNet
    node_map: np.ndarray
    points: np.ndarray
    seam_gaps: np.ndarray
    relaxation: RelaxResult
    settling: RelaxResult
    dt: float

    @property
    def max_seam_gap(self) -> float:
        """Largest seam gap [m] when the seams were joined."""
        return float(self.seam_gaps.max()) if len(self.seam_gaps) else 0.0

    def ignored_parts(self) -> np.ndarray:
        """The body parts each sewn node passes through (:mod:`party.garment.body_parts`)."""
        return sewn_ignored_parts(self.garment, self.node_map)


@dataclass
class SewingStage:
    """Where a sewing stood after one of its stages (:func:`sew`), to go on from: ``stage``
    "sewn" (the first stage's rounds), "closed" (the closing), "spreading" or "settling"
    (``rounds`` of that phase of the settling done), the node positions [m] then (the panels'
    nodes for the first two, the joined garment's after), the relaxation's step ``dt`` [s], the
    logs so far (``relaxation``: the first two stages; ``settling``: both phases), the elements
    beyond the phase's threshold (``settings.spread_beyond``, ``settings.overstretched``) before
    each round and their total length beyond their limits [m] (``excess``), the seam gaps [m]
    at the join, and the joined garment's positions [m] once spread (``spread``)."""

    stage: str
    points: np.ndarray
    dt: float
    relaxation: RelaxResult
    settling: RelaxResult = field(default_factory=RelaxResult)
    overstretched: list[int] = field(default_factory=list)
    rounds: int = 0
    seam_gaps: np.ndarray | None = None
    excess: list[float] = field(default_factory=list)
    spread: np.ndarray | None = None


def sew(garment: Garment, body: Body, fabric: Fabric, settings: SewingSettings = SewingSettings(), *,
        device: str | None = None, progress: bool = False, resume: SewingStage | None = None,
        on_stage: Callable[[SewingStage], None] | None = None, stop: Callable[[], bool] | None = None) -> Sewn:
    """Place ``garment`` around ``body``, sew it closed and return the sewn garment.

    Three relaxations, all with the paper's explicit steps:

    1. the panels pulled together by sewing springs (plastic limit off, so that seams can
       close before the cloth has slid into place; cloth-cloth collision off, see the module
       docstring), for ``settings.max_iterations``, in up to ``settings.rounds`` rounds while
       a pair is more than ``settings.open_gap`` apart;
    2. closing: each sewing spring also gets a plastic limit of ``settings.closed_gap``, which
       pulls the last millimetres shut as a constraint, body collision on;
    3. the joined garment (paired nodes merged), its crossings undone, with cloth-cloth
       collision on (contacts sliding freely, ``settings.exchange``), so that the dynamics
       start from a net within its limits: first, where ``settings.settling_limit`` is above
       the fabric's limit, with the plastic limit there (the spreading), then at the fabric's
       own (the settling), each for more rounds while it pulls back what the first stage
       overstretched (``settings.settling_rounds``); the spread garment is kept where the
       fabric's limit gathered its stretch beyond the gate.

    ``on_stage(stage)`` is called after the first stage, the closing and each settling round
    (:class:`SewingStage`), and a sewing given one as ``resume`` goes on after it. Each stage
    and round starts from the positions the last one left, at rest, so a resumed sewing goes on
    as it would have, but for the memory of the settling's collision searches and crossing guard.

    ``stop()`` true (the drape's time is up) ends the first stage's and the settling's rounds
    where they are; the closing, the first settling round and the settling of what the
    untangling moved always run, so that a garment comes out joined.
    """
    net, node_map = garment.sewn()
    pairs = sewing_pairs(node_map)
    stage = resume.stage if resume else None
    result = resume.relaxation.copy() if resume else RelaxResult()
    if stage is None:
        model = _panels_model(garment, fabric, dress(garment, body, device=device or "cpu"), body, pairs, np.inf,
                              settings, device)
        dt = SolverExplicit.relaxation_step(model)
        state = model.state()
        sewing = StaticRelaxation(model, collision=presets.SEWING, max_speed=settings.sewing_speed,
                                  momentum=settings.momentum)
        iterations = settings.max_iterations
        for round_ in range(settings.rounds):
            if round_ and (result.converged or _pair_gaps(state.positions(), pairs).max(initial=0.0) <= settings.open_gap
                           or (stop is not None and stop())):
                break
            with relax_progress("sewing" if round_ == 0 else "sewing on", iterations, progress) as on_log:
                more = sewing.relax(state, dt, max_iterations=iterations, min_iterations=min(400, iterations),
                                    on_log=on_log, should_stop=stop)
            result.extend(more)
        points = _finite(state.positions())
        stage = _reached(on_stage, SewingStage("sewn", points, dt, result))
    else:
        points, dt = resume.points, resume.dt
    if stage == "sewn" and len(pairs):
        closing = _panels_model(garment, fabric, points, body, pairs,
                                settings.closed_gap / settings.seam_rest_length - 1.0, settings, device)
        state = closing.state()
        steps = settings.stage_iterations
        with relax_progress("closing seams", steps, progress) as on_log:
            # the same masses and stiffnesses as the sewing model (only the seams' limit is new): same dt
            closed = StaticRelaxation(closing, collision=presets.SEWING, max_speed=settings.settling_speed).relax(
                state, dt, max_iterations=steps, min_iterations=min(100, steps), on_log=on_log)
        result.iterations += closed.iterations
        points = _finite(state.positions())
        stage = _reached(on_stage, SewingStage("closed", points, dt, result))
    if stage in SETTLING_PHASES:
        seam_gaps, merged = resume.seam_gaps, points
    else:
        pair_gap = _pair_gaps(points, garment.seam_pairs)
        seam_gaps = np.zeros(len(garment.pattern.seams))
        np.maximum.at(seam_gaps, garment.seam_of_pair, pair_gap)
        merged = np.zeros((net.node_count, 3))
        np.add.at(merged, node_map, points)
        merged /= np.bincount(node_map, minlength=net.node_count)[:, None]
        merged, _ = untangle(merged, net.triangles, device=device)

    gamma, kappa = settings.exchange

    def joined_model(limit: float, points: np.ndarray) -> Model:
        return garment_model(net, fabric.with_(friction=0.0, momentum_propagation=gamma, cloth_friction=kappa,
                                               strain_limit=limit), points, body, gravity=False, device=device,
                             sewn=False, ignored_parts=sewn_ignored_parts(garment, node_map))

    resumed = stage in SETTLING_PHASES
    tail = resume.settling.copy() if resumed else RelaxResult()
    overstretched = list(resume.overstretched) if resumed else []
    excess = list(resume.excess) if resumed else []
    spread = resume.spread if resumed else None
    spreading = max(settings.settling_limit, fabric.strain_limit)
    phases = [("spreading", spreading, settings.spread_beyond), ("settling", fabric.strain_limit, settings.overstretched)]
    for phase, limit, beyond in phases:
        if phase == "spreading" and (stage == "settling" or limit == fabric.strain_limit):
            continue  # done before the resumed run, or nothing to spread beyond the fabric's own limit
        joined = joined_model(limit, merged)
        state = joined.state()
        settle = settings.stage_iterations
        settling = StaticRelaxation(joined, collision=presets.SETTLING, max_speed=settings.settling_speed)
        settling_dt = SolverExplicit.relaxation_step(joined)
        first = resume.rounds if stage == phase else 0
        for round_ in range(first, settings.settling_rounds):
            count, total = _overstretched(joined, state.positions(), beyond)
            overstretched.append(count)
            excess.append(total)
            if round_ and (count == 0 or total > (1.0 - settings.settling_progress) * excess[-2]
                           or (stop is not None and stop())):
                break
            title = "settling seams" if phase == "settling" else "spreading the stretch"
            with relax_progress(title if round_ == 0 else f"{phase} on", settle, progress) as on_log:
                more = settling.relax(state, settling_dt, max_iterations=settle, min_iterations=min(100, settle),
                                      on_log=on_log)
            tail.extend(more)
            _reached(on_stage, SewingStage(phase, _finite(state.positions()), dt, result, tail, list(overstretched),
                                           round_ + 1, seam_gaps, list(excess), spread))
        if phase == "spreading":
            spread = merged = _finite(state.positions())
    if spread is not None:
        worst = _largest_stretch(joined, state.positions())
        if worst > settings.spread_beyond and worst > _largest_stretch(joined, spread):
            # no shape meets the fabric's limit: it gathered the stretch the spreading had spread
            joined = joined_model(spreading, spread)
            state = joined.state()
    settled = _finite(state.positions())
    points, _ = untangle(settled, net.triangles, device=device)
    if np.abs(points - settled).max(initial=0.0) > settings.closed_gap:
        state.node_q.assign(points.astype(np.float32))
        state.node_qd.zero_()
        guarded = StaticRelaxation(joined, collision=presets.settling_guarded(settling_dt),
                                   max_speed=settings.settling_speed)
        with relax_progress("settling the untangled", settle, progress) as on_log:
            tail.extend(guarded.relax(state, settling_dt, max_iterations=settle, min_iterations=min(100, settle),
                                      on_log=on_log))
        points = _finite(state.positions())
    return Sewn(garment, net, node_map, points, seam_gaps, result, tail, dt)


SETTLING_PHASES = ("spreading", "settling")
"""The sewing stages after the join: the spreading (:attr:`SewingSettings.settling_limit`), then
the settling at the fabric's limit."""


def _reached(on_stage: Callable[[SewingStage], None] | None, stage: SewingStage) -> str:
    """Report ``stage`` to ``on_stage``, its logs as they are now; its name."""
    if on_stage is not None:
        on_stage(replace(stage, relaxation=stage.relaxation.copy(), settling=stage.settling.copy()))
    return stage.stage


def _panels_model(garment: Garment, fabric: Fabric, points: np.ndarray, body: Body, pairs: np.ndarray,
                  seam_strain_limit: float, settings: SewingSettings, device: str | None) -> Model:
    """The unsewn panels at ``points`` [m] without gravity, skin friction or plastic limit,
    tied by sewing springs between node ``pairs`` with plastic limit ``seam_strain_limit``; its
    nodes pass through the body parts their panels' labels say (:mod:`party.garment.body_parts`)."""
    builder = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    builder.add_cloth(garment.net, fabric.with_(friction=0.0, strain_limit=float("inf")), points, name="panels")
    if len(pairs):
        stiffness = settings.seam_stiffness * float(np.median(builder.element_stiffness))
        builder.add_springs(pairs, stiffness=stiffness, rest_length=settings.seam_rest_length,
                            strain_limit=seam_strain_limit)
    builder.ignore_body_parts(np.arange(garment.node_count), garment_ignored_parts(garment))
    for collider in body.colliders:
        builder.add_collider(collider)
    return builder.finalize(device)


def _stretch(model: Model, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each of ``model``'s elements with a plastic limit at ``points`` [m]: its length over
    its rest length [-], and its length beyond its limit [m] (negative within it)."""
    limited = model.limited_elements
    nodes = model.element_nodes.numpy()[limited]
    length = np.linalg.norm(points[nodes[:, 1]] - points[nodes[:, 0]], axis=1)
    return length / model.element_rest_length.numpy()[limited], length - model.element_max_length.numpy()[limited]


def _overstretched(model: Model, points: np.ndarray, beyond_rest: float) -> tuple[int, float]:
    """How many of ``model``'s elements with a plastic limit ``points`` [m] stretch beyond
    ``beyond_rest`` times their rest length, and their total length beyond their limits [m]."""
    stretch, beyond = _stretch(model, points)
    return int((stretch > beyond_rest).sum()), float(np.maximum(beyond, 0.0).sum())


def _largest_stretch(model: Model, points: np.ndarray) -> float:
    """The largest length over rest length [-] of ``model``'s elements with a plastic limit at
    ``points`` [m]."""
    return float(_stretch(model, points)[0].max(initial=1.0))


def _pair_gaps(points: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Distance [m] between the two nodes of each of ``pairs`` (p, 2)."""
    return np.linalg.norm(points[pairs[:, 0]] - points[pairs[:, 1]], axis=1)


def _finite(points: np.ndarray) -> np.ndarray:
    if not np.all(np.isfinite(points)):
        raise SimulationUnstable("sewing blew up (non-finite positions); try a coarser --spacing")
    return points


def sewing_pairs(node_map: np.ndarray) -> np.ndarray:
    """Every pair of garment nodes that sew into one node (where three or four panels meet, each
    corner is tied to each other one, so that none of them sees the others as cloth to collide
    with), shape (p, 2)."""
    order = np.argsort(node_map, kind="stable")
    groups = np.split(order, np.flatnonzero(np.diff(node_map[order])) + 1)
    pairs = [(a, b) for g in groups if len(g) > 1 for i, a in enumerate(g) for b in g[i + 1:]]
    return np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
