"""The collision settings party's runs use, each built here once."""

from __future__ import annotations

from dataclasses import replace

from .pipeline import CollisionSettings

GUARD_INTERVAL = 1.0 / 300.0
"""Simulated time [s] between two checks of the crossing guard: the implicit solver's step, so
that explicit steps pay for a check every few dozen steps rather than every step, and a node the
guard sends back goes back at most this far."""

BODY_ONLY = CollisionSettings(cloth=False)
"""The body alone: the validation cases, whose cloth cannot meet itself."""

SEWING = CollisionSettings(cloth=False, broad_phase="bvh")
"""Panels pulled together by sewing springs: the body only (panels meeting at an armpit collide
with one another short of their partners), its triangles found with a BVH, which finds the
interval lists' triangles faster."""

SETTLING = replace(SEWING, cloth=True)
"""The joined garment settling after the seams merged: cloth-cloth collision on as well."""


def guard_every(dt: float) -> int:
    """Steps of ``dt`` [s] between crossing-guard checks: one a :data:`GUARD_INTERVAL`."""
    return max(1, int(GUARD_INTERVAL / dt * (1.0 + 1e-9)))


def guarded(dt: float, *, body_vertices: bool = False) -> CollisionSettings:
    """Body and cloth collision with the crossing guard checking every :data:`GUARD_INTERVAL`
    of steps of ``dt`` [s] (the dress's fall, explicit drapes), and with ``body_vertices`` the
    cloth's triangles answering the body's vertices."""
    return CollisionSettings(crossing_guard=True, guard_every=guard_every(dt), body_vertices=body_vertices)


def settling_guarded(dt: float) -> CollisionSettings:
    """:data:`SETTLING` with the crossing guard checking every :data:`GUARD_INTERVAL` of steps of
    ``dt`` [s]: the sewn garment settling after its crossings were untangled, which must not
    make them again while its plastic limit pulls back what the untangling stretched."""
    return replace(SETTLING, crossing_guard=True, guard_every=guard_every(dt))


def large_step(collision: CollisionSettings | None) -> CollisionSettings | None:
    """``collision`` for the implicit solver's large steps: with the crossing guard on, since
    they let more edges slip through each other, cloth triangles answering body vertices
    (:mod:`party.collision.body_vertices`), whose pushes the guard keeps from crossing layers,
    nodes stopped at the body moved onto its shell (``arrive``), not left a step's approach off
    it. The explicit solver keeps the paper's Collision() as printed."""
    if collision is None:
        return None
    return replace(collision, crossing_guard=True, body_vertices=True, arrive=True)
