"""The pattern model: panels with addressable edges, grain lines, seams and placement.

All lengths are metres; importers convert once, on load. A panel's outline runs
counter-clockwise or clockwise (both are accepted); its edges chain end to start.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import shapely

from ..errors import InvalidInput
from .edges import Edge

PARTS = ("front", "back", "left_sleeve", "right_sleeve", "left_leg", "right_leg")
"""Body parts a panel can be wrapped around when the pattern gives no 3-D placement."""

ANCHORS = ("neck", "shoulder", "bust", "waist", "hip")
"""Body heights the top of an automatically placed torso panel can be put at."""

GATHER_LIMIT = 4.0
"""Largest ratio of the two edge lengths of one seam. A seam whose sides differ is sewn with the
longer side gathered evenly onto the shorter (a sleeve into a cuff, a skirt into a waistband:
GarmentCode's designs gather up to about 3 to 1); beyond 4 to 1 no garment gathers, and the
seam is taken as an error."""

GATHER_SLACK = 0.005
"""Length [m] by which two sides of a seam may differ whatever their ratio: sides of a few
millimetres (a pattern's rounding at a corner) differ in ratio by chance."""


@dataclass(frozen=True)
class Placement:
    """Where a flat panel starts in 3-D: ``R @ (u, v, 0) + translation`` [m], then optionally
    bent round a vertical cylinder of ``wrap_radius`` [m] whose axis passes through
    ``wrap_axis`` (x, y) [m], keeping lengths along the panel's horizontal direction."""

    translation: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    wrap_radius: float | None = None
    wrap_axis: tuple[float, float] = (0.0, 0.0)

    def apply(self, uv: np.ndarray) -> np.ndarray:
        """3-D positions [m] of panel points ``uv`` (n, 2)."""
        local = np.column_stack([uv, np.zeros(len(uv))])
        points = local @ self.rotation.T + self.translation
        if self.wrap_radius is None:
            return points
        axis = np.array([*self.wrap_axis, 0.0])
        mid = np.array([*(0.5 * (uv.min(0) + uv.max(0))), 0.0]) @ self.rotation.T + self.translation
        radial = mid - axis
        radial[2] = 0.0
        radial /= max(np.linalg.norm(radial), 1e-9)
        tangent = np.cross([0.0, 0.0, 1.0], radial)
        along = (points - mid) @ tangent
        angle = along / self.wrap_radius
        out = points.copy()
        out[:, :2] = (axis + self.wrap_radius * (np.cos(angle)[:, None] * radial + np.sin(angle)[:, None] * tangent))[:, :2]
        return out


def euler_xyz_degrees(angles) -> np.ndarray:
    """Rotation matrix of intrinsic XYZ Euler angles [deg] (GarmentCode's and Maya's
    convention): R = Rz Ry Rx."""
    ax, ay, az = np.deg2rad(np.asarray(angles, float))
    rx = np.array([[1, 0, 0], [0, np.cos(ax), -np.sin(ax)], [0, np.sin(ax), np.cos(ax)]])
    ry = np.array([[np.cos(ay), 0, np.sin(ay)], [0, 1, 0], [-np.sin(ay), 0, np.cos(ay)]])
    rz = np.array([[np.cos(az), -np.sin(az), 0], [np.sin(az), np.cos(az), 0], [0, 0, 1]])
    return rz @ ry @ rx


@dataclass(frozen=True)
class Panel:
    """A piece of fabric.

    Attributes:
        name: Unique within the pattern.
        edges: The outline, edges chained end to start, closing on itself.
        grain: Unit warp direction in the panel plane, shape (2,).
        part: Body part for automatic placement (one of :data:`PARTS`), or None.
        anchor: For front/back panels placed automatically: the body height their top sits
            at (one of :data:`ANCHORS`).
        placement: 3-D placement, or None to place automatically.
        label: What the panel covers in GarmentCode's words (``body``, ``leg``, ``arm``; empty
            when the pattern does not say): a ``leg`` panel (a skirt's, a pair of trousers')
            does not collide with the arms, as in GarmentCode's simulator.
    """

    name: str
    edges: tuple[Edge, ...]
    grain: np.ndarray
    part: str | None = None
    anchor: str = "shoulder"
    placement: Placement | None = None
    label: str = ""

    def outline(self) -> np.ndarray:
        """Closed outline as a polyline [m] (first point not repeated)."""
        return np.concatenate([e.polyline()[:-1] for e in self.edges])

    def polygon(self) -> shapely.Polygon:
        return shapely.Polygon(self.outline())

    def edge_index(self, ref: int | str) -> int:
        """Index of an edge given by index or by name."""
        if isinstance(ref, (int, np.integer)) and not isinstance(ref, bool):
            if not 0 <= ref < len(self.edges):
                raise InvalidInput(f"panel {self.name!r} has no edge {ref} (it has {len(self.edges)} edges)")
            return int(ref)
        names = [e.name for e in self.edges]
        if ref not in names:
            raise InvalidInput(f"panel {self.name!r} has no edge named {ref!r}")
        if names.count(ref) > 1:
            raise InvalidInput(f"panel {self.name!r}: edge name {ref!r} is not unique; refer to it by index")
        return names.index(ref)


@dataclass(frozen=True)
class EdgeRef:
    panel: str
    edge: int

    def __str__(self) -> str:
        return f"{self.panel}.edge[{self.edge}]"


@dataclass(frozen=True)
class Seam:
    """Two edges sewn together. ``same_direction`` False (the default, GarmentCode's too) joins
    the start of ``a`` to the end of ``b``, right side to right side; True joins start to start
    (GarmentCode's ``right_wrong``). Both edges may be on one panel (a dart)."""

    a: EdgeRef
    b: EdgeRef
    same_direction: bool = False

    def __str__(self) -> str:
        return f"seam {self.a} - {self.b}"


@dataclass(frozen=True)
class Pattern:
    """Panels by name and the seams between them; checked on construction."""

    name: str
    panels: dict[str, Panel]
    seams: tuple[Seam, ...]

    def __post_init__(self) -> None:
        if not self.panels:
            raise InvalidInput(f"pattern {self.name!r} has no panels")
        for panel in self.panels.values():
            check_panel(panel)
        used: dict[EdgeRef, Seam] = {}
        for seam in self.seams:
            if seam.a == seam.b:
                raise InvalidInput(f"{seam} joins an edge to itself; a seam joins two different edges")
            for ref in (seam.a, seam.b):
                if ref.panel not in self.panels:
                    raise InvalidInput(f"{seam}: unknown panel {ref.panel!r}")
                try:
                    self.panels[ref.panel].edge_index(ref.edge)
                except InvalidInput as error:
                    raise InvalidInput(f"{seam}: {error}") from None
                if ref in used:
                    raise InvalidInput(f"{seam}: edge {ref} is already sewn in {used[ref]}")
                used[ref] = seam
            la, lb = self.edge(seam.a).length(), self.edge(seam.b).length()
            if max(la, lb) > GATHER_LIMIT * min(la, lb) + GATHER_SLACK:
                raise InvalidInput(f"{seam}: edge lengths {la * 100:.1f} cm and {lb * 100:.1f} cm would gather "
                                   f"{max(la, lb) / max(min(la, lb), 1e-9):.1f} to 1, beyond the "
                                   f"{GATHER_LIMIT:g} to 1 a garment gathers")

    def edge(self, ref: EdgeRef) -> Edge:
        return self.panels[ref.panel].edges[ref.edge]


def check_panel(panel: Panel) -> None:
    """Raise :class:`InvalidInput` naming the panel (and edge) if it cannot be cut."""
    where = f"panel {panel.name!r}"
    if len(panel.edges) < 2:
        raise InvalidInput(f"{where}: an outline needs at least two edges, got {len(panel.edges)}")
    for k, e in enumerate(panel.edges):
        e.check(f"{where} edge {k}")
    for k, e in enumerate(panel.edges):
        nxt = panel.edges[(k + 1) % len(panel.edges)]
        gap = float(np.hypot(*(e.end - nxt.start)))
        if gap > 1e-6:
            raise InvalidInput(f"{where}: outline is open between edge {k} and edge {(k + 1) % len(panel.edges)} "
                               f"(gap {gap * 1000:.2f} mm)")
    grain = np.asarray(panel.grain, float)
    if grain.shape != (2,) or not np.all(np.isfinite(grain)) or np.hypot(*grain) < 1e-9:
        raise InvalidInput(f"{where}: missing or invalid grain line (a 2-D warp direction)")
    poly = panel.polygon()
    outline = panel.outline()
    flat = np.linalg.svd(outline - outline.mean(axis=0), compute_uv=False)[-1] < 1e-6
    if flat or (poly.is_valid and poly.area < 1e-6):
        raise InvalidInput(f"{where}: outline encloses no area ({poly.area * 1e4:.3g} cm^2): its vertices lie on "
                           "a line or on top of each other")
    if not poly.is_valid:
        raise InvalidInput(f"{where}: outline crosses itself ({shapely.is_valid_reason(poly)}); check the order of "
                           "its vertices")
    if panel.part is not None and panel.part not in PARTS:
        raise InvalidInput(f"{where}: unknown part {panel.part!r} (expected one of {', '.join(PARTS)})")
    if panel.anchor not in ANCHORS:
        raise InvalidInput(f"{where}: unknown anchor {panel.anchor!r} (expected one of {', '.join(ANCHORS)})")
    if panel.placement is not None:
        p = panel.placement
        if not (np.all(np.isfinite(p.translation)) and np.all(np.isfinite(p.rotation))):
            raise InvalidInput(f"{where}: placement has a non-finite translation or rotation")
        if p.wrap_radius is not None and not (np.isfinite(p.wrap_radius) and p.wrap_radius > 0):
            raise InvalidInput(f"{where}: wrap radius must be positive, got {p.wrap_radius}")
