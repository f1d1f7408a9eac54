"""Resuming ``party drape``: what a drape has done so far, kept in ``OUT/checkpoint.npz``.

A drape saves its checkpoint after each stage of the sewing (:class:`~party.garment.sewing.SewingStage`:
the first stage, the closing, each round of the settling), once the garment is sewn, and while
it drapes at most every :data:`SAVE_SECONDS` of wall time (atomically:
:func:`~party.output.frames.save_checkpoint`). ``party drape ... --resume`` reads it and goes on
from there: the sewing from the stage it had finished, the draping from the saved positions [m]
and velocities [m/s], step count and energy log. A sewing stage starts from the positions the
last left, at rest, so a sewing goes on as it would have (bit for bit but after a settling
round, whose collision memory starts afresh). The draping solver's own memory (the implicit
solver's Chebyshev history and body planes, the crossing guard's last checked positions) starts
afresh, so a drape resumed while draping takes another path from there than one run through:
it comes to rest as one does, not to the same bits. A drape
that finishes replaces OUT, its checkpoint with it; a checkpoint of a drape asked for with
other inputs is refused with a one-line error.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Callable

import numpy as np

from ..body.body import Body
from ..errors import InvalidInput
from ..fabric import Fabric
from ..garment.assemble import Garment
from ..model import State
from ..output.frames import load_checkpoint, save_checkpoint
from ..solvers.relax import RelaxResult
from ..garment.sewing import Sewn, SewingSettings, SewingStage, sew

SAVE_SECONDS = 10.0
"""Least wall time [s] between two saves while draping."""

Saved = Callable[[str, int], None]
"""``on_save(stage, step)``, called after each save: ``stage`` a sewing stage's name
(:class:`~party.garment.sewing.SewingStage`: "sewn", "closed", "spreading", "settling"), "garment" once sewn,
or "draping"; ``step`` the settling's rounds or the draping's steps (else 0)."""


class DrapeCheckpoint:
    """The checkpoint at ``path`` of the drape asked for with ``inputs`` (a JSON-able dict:
    pattern, body, fabric, spacing, solver, ...), which a resumed drape must match; ``run``
    names what it is a checkpoint of in the errors (``party run dress`` keeps its sewing in
    one: :mod:`.dress`). While draping it saves at most every ``save_every`` [s] of wall time;
    ``on_save`` (:data:`Saved`) hears of every save."""

    def __init__(self, path: Path, inputs: dict, run: str = "drape", *, save_every: float = SAVE_SECONDS,
                 on_save: Saved | None = None) -> None:
        self.path = Path(path)
        self.inputs = json.dumps(inputs, sort_keys=True)
        self.run = run
        self.save_every = save_every
        self.on_save = on_save
        self._sewn: dict = {}
        self._saved_at = -math.inf

    def load(self) -> dict | None:
        """The saved arrays, or None where there is no checkpoint; raises :class:`InvalidInput`
        naming the inputs that differ where it belongs to another drape."""
        if not self.path.exists():
            return None
        saved = load_checkpoint(self.path)
        try:
            theirs = json.loads(str(saved["inputs"]))
            if not isinstance(theirs, dict):
                raise ValueError("its inputs are not a record")
        except (ValueError, KeyError):
            raise InvalidInput(f"{self.path} is not a {self.run} checkpoint (it records no inputs); remove it or "
                               "drop --resume") from None
        ours = json.loads(self.inputs)
        differing = sorted(k for k in ours.keys() | theirs.keys()  # as written: a NaN equals itself there
                           if json.dumps(ours.get(k), sort_keys=True) != json.dumps(theirs.get(k), sort_keys=True))
        if differing:
            raise InvalidInput(f"{self.path} belongs to another {self.run} (different {', '.join(differing)}); "
                               "remove it or drop --resume")
        self._sewn = {k: saved[k] for k in saved if k.startswith("sewn_") or k == "wall_seconds"}
        return saved

    @staticmethod
    def sewing_stage(saved: dict | None) -> SewingStage | None:
        """The sewing stage ``saved`` (:meth:`load`) had finished, where it had not finished the
        sewing (None where it had, or where there is none)."""
        if saved is None or "sewing_stage" not in saved or "sewn_points" in saved:
            return None
        return SewingStage(
            str(saved["sewing_stage"]), saved["sewing_points"].astype(np.float64), float(saved["sewing_dt"]),
            _log(saved, "sewing"), _log(saved, "settling"), [int(n) for n in saved["overstretched"]],
            int(saved["rounds"]), saved["seam_gaps"] if saved["seam_gaps"].size else None,
            [float(x) for x in saved.get("excess", ())],
            saved["spread_points"].astype(np.float64) if saved.get("spread_points", np.empty(0)).size else None)

    def save_sewing(self, stage: SewingStage, wall_seconds: float) -> None:
        """Save the sewing as it stood after ``stage``, ``wall_seconds`` [s] into the drape."""
        self._write(sewing_stage=stage.stage, sewing_points=stage.points.astype(np.float64), sewing_dt=stage.dt,
                    **_log_arrays(stage.relaxation, "sewing"), **_log_arrays(stage.settling, "settling"),
                    overstretched=np.asarray(stage.overstretched, np.int64),
                    excess=np.asarray(stage.excess, np.float64), rounds=stage.rounds,
                    seam_gaps=np.asarray([] if stage.seam_gaps is None else stage.seam_gaps, np.float64),
                    spread_points=np.asarray([] if stage.spread is None else stage.spread, np.float64),
                    wall_seconds=wall_seconds)
        self._said(stage.stage, stage.rounds)

    def sewn(self, garment: Garment, saved: dict) -> Sewn:
        """The sewn garment of ``saved`` (:meth:`load`) on ``garment``, the same pattern meshed again."""
        net, node_map = garment.sewn()
        points = saved["sewn_points"].astype(np.float64)
        if points.shape != (net.node_count, 3):
            raise InvalidInput(f"{self.path} holds {len(points)} sewn nodes where this pattern has {net.node_count}; "
                               "remove it or drop --resume")
        return Sewn(garment, net, node_map, points, saved["sewn_seam_gaps"], _log(saved, "sewn"),
                    _log(saved, "sewn_settling"), float(saved["sewn_dt"]))

    @staticmethod
    def wall_clock(saved: dict | None, started: float) -> Callable[[], float]:
        """The run's wall time [s] so far: what ``saved`` (:meth:`load`) had recorded, plus the
        time since ``started`` (a :func:`time.perf_counter` reading)."""
        earlier = float(saved["wall_seconds"]) if saved else 0.0
        return lambda: earlier + time.perf_counter() - started

    def sew(self, saved: dict | None, wall: Callable[[], float], garment: Garment, body: Body, fabric: Fabric,
            settings: SewingSettings, **options) -> Sewn:
        """The sewn garment ``saved`` (:meth:`load`) holds; else :func:`~party.garment.sewing.sew`
        with ``settings`` and ``options`` (device, progress), gone on from the stage ``saved``
        had finished (if any), saved after each stage and once sewn with ``wall()`` [s] of the
        run by then."""
        if saved is not None and "sewn_points" in saved:
            return self.sewn(garment, saved)
        sewn = sew(garment, body, fabric, settings, resume=self.sewing_stage(saved),
                   on_stage=lambda stage: self.save_sewing(stage, wall()), **options)
        self.save_sewn(sewn, wall())
        return sewn

    def save_sewn(self, sewn: Sewn, wall_seconds: float) -> None:
        """Save the garment as sewn, after ``wall_seconds`` [s] of the drape."""
        self._sewn = {
            "sewn_points": sewn.points.astype(np.float64), "sewn_seam_gaps": np.asarray(sewn.seam_gaps, np.float64),
            **_log_arrays(sewn.relaxation, "sewn"), **_log_arrays(sewn.settling, "sewn_settling"),
            "sewn_dt": sewn.dt, "wall_seconds": wall_seconds,
        }
        self._write(**self._sewn)
        self._said("garment", 0)

    def save_draping(self, state: State, step: int, energy: list, wall_seconds: float, *, now: bool = False) -> None:
        """Save the draping ``state`` after ``step`` steps (iterations) with its ``energy`` log
        [(step, J)], ``wall_seconds`` [s] into the drape; at most every ``save_every``, unless
        ``now``."""
        if not now and time.perf_counter() - self._saved_at < self.save_every:
            return
        self._write(**{**self._sewn, "wall_seconds": wall_seconds}, node_q=state.positions(),
                    node_qd=state.velocities(), draping_step=step,
                    draping_energy=np.asarray(energy, np.float64).reshape(-1, 2))
        self._said("draping", step)

    def _said(self, stage: str, step: int) -> None:
        if self.on_save is not None:
            self.on_save(stage, step)

    def _write(self, **arrays) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        save_checkpoint(self.path, inputs=self.inputs, **arrays)
        self._saved_at = time.perf_counter()


def _log_arrays(log: RelaxResult, name: str) -> dict:
    """A relaxation's log as the checkpoint's arrays ``name_energy``, ``name_iterations`` and
    ``name_converged``; :func:`_log` reads them back."""
    return {f"{name}_energy": np.asarray(log.energy, np.float64).reshape(-1, 2), f"{name}_iterations": log.iterations,
            f"{name}_converged": log.converged}


def _log(saved: dict, name: str) -> RelaxResult:
    return RelaxResult(int(saved[f"{name}_iterations"]), [(int(i), float(e)) for i, e in saved[f"{name}_energy"]],
                       bool(saved[f"{name}_converged"]))


def restore_draping(state: State, saved: dict | None) -> tuple[int, list]:
    """Put the saved draping positions and velocities into ``state``; the steps taken and the
    energy log [(step, J)] (0 and [] where the drape had not begun)."""
    if saved is None or "node_q" not in saved:
        return 0, []
    if saved["node_q"].shape != (state.node_q.shape[0], 3):
        raise InvalidInput("the checkpoint's draping state does not fit this garment; remove it or drop --resume")
    state.node_q.assign(saved["node_q"].astype(np.float32))
    state.node_qd.assign(saved["node_qd"].astype(np.float32))
    return int(saved["draping_step"]), [(int(s), float(e)) for s, e in saved["draping_energy"].tolist()]
