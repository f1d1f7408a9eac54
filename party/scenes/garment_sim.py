"""Sewing a garment onto a body and building the model of the sewn garment.

Sewing (set-up): the panels, placed around the body, are joined by zero-length sewing springs
between paired seam nodes and relaxed ignoring inertia (:mod:`party.solvers.relax`) without
gravity, skin friction or plastic limit, body collision on, until the energy settles; the
paired nodes are then merged, so the garment becomes one connected net whose rest lengths are
the flat pattern's, and relaxed again with cloth-cloth collision on as well.

Cloth-cloth collision waits for the merge: while springs pull the panels together, the panels
meeting at an armpit (front, back and two sleeve halves) collided with one another short of
their partners. GarmentCode's tshirt at 30 mm kept seam gaps of 17 mm and merged into 102
crossings that way; sewn without it, every gap closed to 0.5 mm with no crossing. A crossing
made while sewing would stay in the garment, since collision response keeps each node on the
side of a layer it is on: before the joined garment relaxes with cloth-cloth collision on, the
crossings are undone (:func:`party.collision.untangle.untangle`). GarmentCode's tshirt at 20 mm
was sewn with 15 in denim and 14 in silk, each where a sleeve panel had folded through itself at
the armpit; untangling the denim one moved nodes by up to 8 mm. ``party drape`` and ``party
run dress`` count the crossings of every result they write.
"""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from ..body.body import Body
from ..collision import CollisionSettings
from ..collision.untangle import untangle
from ..errors import SimulationUnstable
from ..fabric import Fabric
from ..garment.assemble import Garment
from ..garment.dressing import dress
from ..meshing.net import ClothNet
from ..model import Model, ModelBuilder
from ..solvers.explicit.solver import critical_time_step
from ..solvers.relax import RelaxResult, SolverRelax
from ..solvers.select import DEFAULT_DT

SEAM_REST_LENGTH = 1.0e-4
"""Rest length of a sewing spring [m] (zero in effect; a spring needs a direction)."""

CLOSED_GAP = 5.0e-4
"""Largest distance [m] between paired seam nodes that the closing stage allows."""

MOMENTUM = 0.9

SEWING_COLLISION = CollisionSettings(cloth=False, broad_phase="bvh")
"""Collision while sewing: the body only (see the module docstring), its triangles found with a
BVH, which finds the interval lists' triangles faster (the paper's lists stay with the
simulations proper)."""

OPEN_GAP = 0.01
"""Largest distance [m] between paired seam nodes at which the sewing's first stage may stop
short of its energy settling; beyond it the stage goes on for up to :data:`SEWING_ROUNDS`
times its iterations. Stiff fabrics take smaller explicit steps and so need more of them:
GarmentCode's jumpsuit in denim at 20 mm still had seams 227 mm apart after 6,000 iterations
and closed in 18,450."""

SEWING_ROUNDS = 4
"""Most rounds of ``max_iterations`` the sewing's first stage takes while seams are open."""

SETTLING_EXCHANGE = (1.0, 1.0)
"""The settling's cloth-cloth exchange (gamma, kappa of eqs. 13-14): with both 1 a contact only
stops the approach along its normal and leaves the sliding along the layer as it was, as the
sewing leaves out skin friction. The fabric's own (wool flannel's 0.5 and 0.23) cut a node's
whole velocity in contact to a tenth, sliding included, and the plastic limit's pull with it:
GarmentCode's flare dress at 9 mm kept a neckline edge caught between layers at 1.97 times its
limit through every iteration of six rounds, the limit's 32 sweeps undone by each Collision()
(docs/design.md, Sewing)."""

SETTLING_ROUNDS = 10
OVERSTRETCHED = 1.5
SETTLING_PROGRESS = 0.05
"""The settling stage (the joined garment under its plastic limit) goes on for up to
``SETTLING_ROUNDS`` rounds of its iterations while elements are still stretched beyond
``OVERSTRETCHED`` times their rest length, as long as each round cuts the elements' total length
beyond their limits by at least ``SETTLING_PROGRESS`` of what it was. The first stage, which has
no plastic limit, can leave a panel stretched where seams pulled it faster than it could slide:
GarmentCode's jumpsuit at 30 mm came out of it with the front bodice's top row stretched to 4
times rest over the shoulders, and after one round of settling still 5.0, which the drape would
have kept as worn stretch (:func:`garment_model`); after four rounds 1.24, the bodice over the
shoulders. A pattern that is smaller than its wearer stays stretched however long it settles, and
stops once a round shows it (GarmentCode's pencil dress at 20 mm in cotton: its excess 1,147,
699, 468, 430 and 413 mm, four rounds). Progress is the excess, not the count beyond 1.5: as the
limit pulls a stretched panel back, its stretch gathers in the fewest elements the body holds
out, whose count and largest stretch may rise for a round or two while the whole falls (the
jumpsuit at 20 mm in denim: 140, 140 and 170 elements beyond 1.5, up to 2.9, 5.5 and 6.3 times
rest, while its excess fell from 9.1 m to 6.2 and 4.8; stopped by the count after one round, it
was sewn at 5.45 with 140 elements beyond 1.5, after six rounds at 3.5 with 12, and after nine at
1.49 with none). Nor does a round whose energy settled stop them: stiff cloth's small steps
change the energy slowly while it still pulls back (the jumpsuit at 20 mm in cotton settled in
750 iterations with 184 elements beyond 1.5, up to 7.6; two more rounds left none)."""

SEAM_STIFFNESS = 4.0
"""Sewing spring constant as a multiple of the fabric's median element constant: stiff enough
to close seams to well under a millimetre against the cloth's pull. It sets the sewing's stable
step (GarmentCode's flare dress at 20 mm in wool flannel: 6.4e-5 s, against 1.9e-4 s for its
panels alone; fictitious masses that lift that limit were tried, see docs/design.md, Sewing)."""


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


def garment_model(net: ClothNet, fabric: Fabric, points: np.ndarray, body: Body, *, gravity: bool = True,
                  device: str | None = None, name: str = "garment", sewn: bool = True) -> Model:
    """The model of a garment ``net`` at ``points`` [m] on ``body``. Once ``sewn``, elements
    that ``points`` stretch beyond the fabric's strain limit keep that length as their limit
    (:meth:`ModelBuilder.yield_to_placement`): a pattern smaller than its wearer can only be
    worn stretched, and the plastic limit, fighting the body's collision response for a length
    it cannot reach, let the stretch grow every step instead (GarmentCode's pencil dress on
    mean_all, sewn with its waist at 1.5 times rest: 4.9 within 0.25 s of implicit draping)."""
    builder = ModelBuilder() if gravity else ModelBuilder(gravity=(0.0, 0.0, 0.0))
    builder.add_cloth(net, fabric, points, name=name)
    if sewn:
        builder.yield_to_placement()
    for collider in body.colliders:
        builder.add_collider(collider)
    return builder.finalize(device)


@dataclass
class SewingStage:
    """Where a sewing stood after one of its stages (:func:`sew`), to go on from: ``stage``
    "sewn" (the first stage's rounds), "closed" (the closing) or "settling" (``rounds`` of the
    settling done), the node positions [m] then (the panels' nodes for the first two, the joined
    garment's for the last), the relaxation's step ``dt`` [s], the logs so far (``relaxation``:
    the first two stages; ``settling``), the elements beyond :data:`OVERSTRETCHED` before each
    settling round and their total length beyond their limits [m] (``excess``), and the seam gaps
    [m] at the join."""

    stage: str
    points: np.ndarray
    dt: float
    relaxation: RelaxResult
    settling: RelaxResult = field(default_factory=RelaxResult)
    overstretched: list[int] = field(default_factory=list)
    rounds: int = 0
    seam_gaps: np.ndarray | None = None
    excess: list[float] = field(default_factory=list)


def sew(garment: Garment, body: Body, fabric: Fabric, *, device: str | None = None, max_iterations: int = 6000,
        progress: bool = False, resume: SewingStage | None = None,
        on_stage: Callable[[SewingStage], None] | None = None) -> Sewn:
    """Place ``garment`` around ``body``, sew it closed and return the sewn garment.

    Three relaxations, all with the paper's explicit steps:

    1. the panels pulled together by sewing springs (plastic limit off, so that seams can
       close before the cloth has slid into place; cloth-cloth collision off, see the module
       docstring), up to ``max_iterations``, or up to :data:`SEWING_ROUNDS` times that while
       a pair is more than :data:`OPEN_GAP` apart;
    2. closing: each sewing spring also gets a plastic limit of :data:`CLOSED_GAP`, which
       pulls the last millimetres shut as a constraint (the springs alone leave a gap where
       the cloth pulls against them: 5 mm on GarmentCode's jumpsuit), body collision on;
    3. the joined garment (paired nodes merged), its crossings undone, with its own plastic
       limit and cloth-cloth collision on (contacts sliding freely, :data:`SETTLING_EXCHANGE`),
       so that the dynamics start from a net within its limits; for more rounds while it pulls
       back what the first stage overstretched (:data:`SETTLING_ROUNDS`).

    ``on_stage(stage)`` is called after the first stage, the closing and each settling round
    (:class:`SewingStage`), and a sewing given one as ``resume`` goes on after it. Each stage
    and round starts from the positions the last one left, at rest, so a resumed sewing goes on
    as it would have, but for the memory of the settling's collision searches and crossing guard.
    """
    net, node_map = garment.sewn()
    pairs = sewing_pairs(node_map)
    stage = resume.stage if resume else None
    result = resume.relaxation.copy() if resume else RelaxResult()
    if stage is None:
        model = _panels_model(garment, fabric, dress(garment, body, device=device or "cpu"), body, pairs, np.inf,
                              device)
        dt = relax_time_step(model, "explicit")
        state = model.state()
        sewing = SolverRelax(model, collision=SEWING_COLLISION, max_speed=4.0, momentum=MOMENTUM)
        for round_ in range(SEWING_ROUNDS):
            if round_ and (result.converged or _pair_gaps(state.positions(), pairs).max(initial=0.0) <= OPEN_GAP):
                break
            with relax_progress("sewing" if round_ == 0 else "sewing on", max_iterations, progress) as on_log:
                more = sewing.relax(state, dt, max_iterations=max_iterations, min_iterations=min(400, max_iterations),
                                    on_log=on_log)
            result.extend(more)
        points = _finite(state.positions())
        stage = _reached(on_stage, SewingStage("sewn", points, dt, result))
    else:
        points, dt = resume.points, resume.dt
    if stage == "sewn" and len(pairs):
        closing = _panels_model(garment, fabric, points, body, pairs, CLOSED_GAP / SEAM_REST_LENGTH - 1.0, device)
        state = closing.state()
        steps = max(max_iterations // 4, 200)
        with relax_progress("closing seams", steps, progress) as on_log:
            # the same masses and stiffnesses as the sewing model (only the seams' limit is new): same dt
            closed = SolverRelax(closing, collision=SEWING_COLLISION, max_speed=1.0).relax(
                state, dt, max_iterations=steps, min_iterations=min(100, steps), on_log=on_log)
        result.iterations += closed.iterations
        points = _finite(state.positions())
        stage = _reached(on_stage, SewingStage("closed", points, dt, result))
    if stage == "settling":
        seam_gaps, merged = resume.seam_gaps, points
    else:
        pair_gap = _pair_gaps(points, garment.seam_pairs)
        seam_gaps = np.zeros(len(garment.pattern.seams))
        np.maximum.at(seam_gaps, garment.seam_of_pair, pair_gap)
        merged = np.zeros((net.node_count, 3))
        np.add.at(merged, node_map, points)
        merged /= np.bincount(node_map, minlength=net.node_count)[:, None]
        merged, _ = untangle(merged, net.triangles, device=device)

    gamma, kappa = SETTLING_EXCHANGE
    joined = garment_model(net, fabric.with_(friction=0.0, momentum_propagation=gamma, cloth_friction=kappa), merged,
                           body, gravity=False, device=device, sewn=False)
    state = joined.state()
    settle = max(max_iterations // 4, 200)
    settling = SolverRelax(joined, collision=replace(SEWING_COLLISION, cloth=True), max_speed=1.0)
    settling_dt = relax_time_step(joined, "explicit")
    resumed = stage == "settling"
    tail = resume.settling.copy() if resumed else RelaxResult()
    overstretched = list(resume.overstretched) if resumed else []
    excess = list(resume.excess) if resumed else []
    for round_ in range(resume.rounds if resumed else 0, SETTLING_ROUNDS):
        count, total = _overstretched(joined, state.positions())
        overstretched.append(count)
        excess.append(total)
        if round_ and (count == 0 or (len(excess) > 1 and total > (1.0 - SETTLING_PROGRESS) * excess[-2])):
            break
        with relax_progress("settling seams" if round_ == 0 else "settling on", settle, progress) as on_log:
            more = settling.relax(state, settling_dt, max_iterations=settle, min_iterations=min(100, settle),
                                  on_log=on_log)
        tail.extend(more)
        _reached(on_stage, SewingStage("settling", _finite(state.positions()), dt, result, tail, list(overstretched),
                                       round_ + 1, seam_gaps, list(excess)))
    points, _ = untangle(_finite(state.positions()), net.triangles, device=device)
    return Sewn(garment, net, node_map, points, seam_gaps, result, tail, dt)


def _reached(on_stage: Callable[[SewingStage], None] | None, stage: SewingStage) -> str:
    """Report ``stage`` to ``on_stage``, its logs as they are now; its name."""
    if on_stage is not None:
        on_stage(replace(stage, relaxation=stage.relaxation.copy(), settling=stage.settling.copy()))
    return stage.stage


def _panels_model(garment: Garment, fabric: Fabric, points: np.ndarray, body: Body, pairs: np.ndarray,
                  seam_strain_limit: float, device: str | None) -> Model:
    """The unsewn panels at ``points`` [m] without gravity, skin friction or plastic limit,
    tied by sewing springs between node ``pairs`` with plastic limit ``seam_strain_limit``."""
    builder = ModelBuilder(gravity=(0.0, 0.0, 0.0))
    builder.add_cloth(garment.net, fabric.with_(friction=0.0, strain_limit=float("inf")), points, name="panels")
    if len(pairs):
        stiffness = SEAM_STIFFNESS * float(np.median(builder.element_stiffness))
        builder.add_springs(pairs, stiffness=stiffness, rest_length=SEAM_REST_LENGTH, strain_limit=seam_strain_limit)
    for collider in body.colliders:
        builder.add_collider(collider)
    return builder.finalize(device)


def relax_time_step(model: Model, solver: str) -> float:
    """The pseudo time step [s] of a relaxation: 0.9 of the explicit stability limit (which
    allows for the dampers), or the implicit solver's default step."""
    return 0.9 * critical_time_step(model) if solver == "explicit" else DEFAULT_DT["implicit"]


def _overstretched(model: Model, points: np.ndarray) -> tuple[int, float]:
    """How many of ``model``'s elements with a plastic limit ``points`` [m] stretch beyond
    :data:`OVERSTRETCHED` times their rest length, and their total length beyond their limits [m]."""
    limited = model.limited_elements
    nodes = model.element_nodes.numpy()[limited]
    length = np.linalg.norm(points[nodes[:, 1]] - points[nodes[:, 0]], axis=1)
    beyond = length - model.element_max_length.numpy()[limited]
    return (int((length > OVERSTRETCHED * model.element_rest_length.numpy()[limited]).sum()),
            float(np.maximum(beyond, 0.0).sum()))


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


@contextmanager
def relax_progress(label: str, total: int, show: bool):
    """A progress bar for a relaxation; yields the ``on_log`` callback to hand to it."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    bar = Progress(TextColumn(f"[bold]{label}[/]"), BarColumn(), TextColumn("{task.completed} iterations"),
                   TextColumn("energy {task.fields[energy]:.4g} J"), TimeElapsedColumn(), disable=not show)
    with bar:
        task = bar.add_task(label, total=total, energy=float("nan"))

        def on_log(iteration: int, energy: float, state) -> None:
            bar.update(task, completed=iteration, energy=energy)

        yield on_log
        bar.update(task, total=bar.tasks[0].completed)
