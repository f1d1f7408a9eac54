"""Quality gates: whether a drape's result is a garment worn on its body, said in its summary.

A drape that misses a gate still writes its results; its ``summary.json`` holds ``quality``:
``passed`` and ``reasons`` (one short line per gate missed), and ``party drape`` prints them in
one warning line, so that no wrong result passes silently.
"""

from __future__ import annotations

MAX_SEAM_GAP_MM = 2.0
"""Largest distance [mm] between the two sides of a seam when they were joined."""

MAX_ELONGATION = 1.3
"""Largest length over rest length of any warp or weft element of the draped garment: beyond
it the cloth holds stretch that the sewing or the collisions put in, not the pattern's fit."""

OFF_BODY_MM = 10.0
"""A garment whose nearest node is farther than this [mm] beyond the collision thickness from
the body is not worn: a garment on a body rests on it somewhere."""

HANGING_OFF_MM = 200.0
"""A garment whose nodes lie farther than this [mm] from the body at the median, and that has
fewer than :data:`NEAR_SHARE` of its nodes within :data:`NEAR_MM` of it, is not worn either,
though it may touch the body somewhere (a jumpsuit caught on a body lying on its side: 593 mm
and 3 %). Fitted garments keep half their cloth within a few centimetres of the body
(GarmentCode's samples: 10 to 44 mm); a full skirt's hem swings wider (a midi skirt of many
panels: 206 mm), but its waist and hips rest on the body (21 % of its nodes)."""

NEAR_MM = 50.0
"""See :data:`HANGING_OFF_MM` [mm]."""

NEAR_SHARE = 0.1
"""See :data:`HANGING_OFF_MM` [-]."""


def drape_quality(summary: dict, thickness: float) -> dict:
    """``{"passed": bool, "reasons": [str, ...]}`` for a drape's ``summary`` (see
    :func:`party.scenes.drape.drape`); ``thickness`` [m] is the fabric's collision thickness."""
    reasons = []
    nearest, median = summary["body_distance_mm"]["nearest"], summary["body_distance_mm"]["median"]
    if nearest > OFF_BODY_MM + 1000.0 * thickness:
        reasons.append(f"not on the body: its nearest node is {nearest:.0f} mm from it")
    elif median > HANGING_OFF_MM and summary["body_distance_mm"]["near_share"] < NEAR_SHARE:
        reasons.append(f"not on the body: half its nodes are more than {median:.0f} mm from it")
    where = summary.get("where", {})
    if summary["body_penetrations"]:
        reasons.append(f"{summary['body_penetrations']} nodes inside the body{_at(where.get('inside'))}")
    if summary["cloth_crossings"]:
        reasons.append(f"{summary['cloth_crossings']} cloth crossings{_at(where.get('crossings'))}")
    if summary["max_seam_gap_mm"] > MAX_SEAM_GAP_MM:
        seam, gap = max(summary["seam_gaps_mm"].items(), key=lambda item: item[1])
        reasons.append(f"seam {seam} left open {gap:.1f} mm by the sewing")
    if summary["max_elongation"] > MAX_ELONGATION:
        reasons.append(f"stretched to {summary['max_elongation']:.2f} times rest (at most {MAX_ELONGATION})"
                       f"{_at(where.get('stretched'))}")
    if not summary["relaxation"]["at_rest"]:
        reasons.append("not at rest at the end of the draping")
    if summary["timed_out"]:
        reasons.append(f"ran past its time limit of {summary['time_limit_s']:g} s and was stopped there")
    return {"passed": not reasons, "reasons": reasons}


STAGES = {"sewing": "since the sewing", "draping": "in the draping"}
"""How a reason says which stage brought a fault (:func:`party.output.locate.locate`)."""


def _at(fault: dict | None) -> str:
    """", in panel 'a' and panel 'b', since the sewing" for a fault located by
    :func:`party.output.locate.locate`; empty where it was not located."""
    if not fault:
        return ""
    panels = " and ".join(f"panel '{name}'" for name in fault["panels"])
    return f", in {panels}, {STAGES[fault['stage']]}" if panels else f", {STAGES[fault['stage']]}"
