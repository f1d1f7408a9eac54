"""Panel outline edges: straight lines, circular arcs and quadratic/cubic Beziers in the flat
pattern plane. Coordinates are metres (importers convert from their units in one place,
:mod:`party.pattern.units`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InvalidInput

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(8)


@dataclass(frozen=True)
class Edge:
    """One edge of a panel outline, from ``start`` to ``end`` [m].

    Attributes:
        kind: ``line``, ``arc``, ``quadratic``, ``cubic`` or ``polyline`` (a digitised chain,
            as DXF pattern files carry; its ``controls`` are the interior points).
        start, end: End points, shape (2,).
        controls: Bezier control points, shape (k, 2) (k = 1 or 2), or a polyline's interior
            points; none for line and arc.
        center: Arc centre, shape (2,); ``ccw`` tells which way the arc runs from start to end.
        name: Optional label (e.g. a GarmentCode edge label or a DXF line's name).
    """

    kind: str
    start: np.ndarray
    end: np.ndarray
    controls: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    center: np.ndarray | None = None
    ccw: bool = True
    name: str = ""

    def __post_init__(self) -> None:
        for attr in ("start", "end", "controls"):
            object.__setattr__(self, attr, np.asarray(getattr(self, attr), float))
        if self.center is not None:
            object.__setattr__(self, "center", np.asarray(self.center, float))

    # --- geometry -------------------------------------------------------------------------
    def _arc_angles(self) -> tuple[float, float, float]:
        """Radius, start angle and signed sweep [rad] of an arc."""
        a, b = self.start - self.center, self.end - self.center
        radius = float(np.hypot(*a))
        t0 = float(np.arctan2(a[1], a[0]))
        sweep = float(np.arctan2(b[1], b[0])) - t0
        if self.ccw:
            sweep = sweep % (2 * np.pi) or 2 * np.pi
        else:
            sweep = -((-sweep) % (2 * np.pi) or 2 * np.pi)
        return radius, t0, sweep

    def point(self, t) -> np.ndarray:
        """Points at curve parameters ``t`` in [0, 1] (not arc length), shape (len(t), 2)."""
        t = np.atleast_1d(np.asarray(t, float))[:, None]
        if self.kind == "polyline":  # t is the arc-length fraction
            pts = self._chain()
            cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
            s = t[:, 0] * cum[-1]
            return np.column_stack([np.interp(s, cum, pts[:, 0]), np.interp(s, cum, pts[:, 1])])
        if self.kind == "line":
            return (1 - t) * self.start + t * self.end
        if self.kind == "arc":
            radius, t0, sweep = self._arc_angles()
            ang = t0 + sweep * t[:, 0]
            return self.center + radius * np.stack([np.cos(ang), np.sin(ang)], axis=1)
        p = [self.start, *self.controls, self.end]
        if self.kind == "quadratic":
            return (1 - t) ** 2 * p[0] + 2 * (1 - t) * t * p[1] + t**2 * p[2]
        return ((1 - t) ** 3 * p[0] + 3 * (1 - t) ** 2 * t * p[1] + 3 * (1 - t) * t**2 * p[2] + t**3 * p[3])

    def _chain(self) -> np.ndarray:
        return np.vstack([self.start, self.controls.reshape(-1, 2), self.end])

    def _speed(self, t: np.ndarray) -> np.ndarray:
        """|dP/dt| at parameters t."""
        p = [self.start, *self.controls, self.end]
        t = t[:, None]
        if self.kind == "quadratic":
            d = 2 * (1 - t) * (p[1] - p[0]) + 2 * t * (p[2] - p[1])
        else:
            d = 3 * (1 - t) ** 2 * (p[1] - p[0]) + 6 * (1 - t) * t * (p[2] - p[1]) + 3 * t**2 * (p[3] - p[2])
        return np.hypot(d[:, 0], d[:, 1])

    def _cumulative_length(self, t: np.ndarray) -> np.ndarray:
        """Arc length from the start to each of the sorted parameters t (Gauss-Legendre)."""
        if self.kind == "line":
            return t * float(np.hypot(*(self.end - self.start)))
        if self.kind == "polyline":
            return t * float(np.hypot(*np.diff(self._chain(), axis=0).T).sum())
        if self.kind == "arc":
            radius, _, sweep = self._arc_angles()
            return t * radius * abs(sweep)
        grid = np.unique(np.concatenate([[0.0], t]))
        a, b = grid[:-1], grid[1:]
        nodes = 0.5 * (b - a)[:, None] * (_GAUSS_X[None, :] + 1) + a[:, None]
        pieces = 0.5 * (b - a) * (self._speed(nodes.ravel()).reshape(nodes.shape) @ _GAUSS_W)
        cum = np.concatenate([[0.0], np.cumsum(pieces)])
        return cum[np.searchsorted(grid, t)]

    def length(self) -> float:
        """Arc length [m] (exact for lines and arcs, Gauss-Legendre to ~1e-12 for Beziers)."""
        return float(self._cumulative_length(np.linspace(0.0, 1.0, 65))[-1])

    def parameters_at_fractions(self, fractions) -> np.ndarray:
        """Curve parameters where the arc length reaches the given fractions of the total."""
        fractions = np.asarray(fractions, float)
        if self.kind in ("line", "arc", "polyline"):
            return fractions
        dense = np.linspace(0.0, 1.0, 1025)
        cum = self._cumulative_length(dense)
        return np.interp(fractions * cum[-1], cum, dense)

    def sample(self, segments: int) -> np.ndarray:
        """``segments + 1`` points spaced evenly by arc length, ends included, shape (n+1, 2)."""
        return self.point(self.parameters_at_fractions(np.linspace(0.0, 1.0, segments + 1)))

    def polyline(self) -> np.ndarray:
        """Points following the curve every 5 mm or closer (for outlines and drawings)."""
        if self.kind in ("line", "polyline"):
            return self._chain()
        return self.sample(int(np.clip(np.ceil(self.length() / 5e-3), 8, 400)))

    # --- editing ----------------------------------------------------------------------------
    def reversed(self) -> "Edge":
        if self.kind == "arc":
            return Edge("arc", self.end, self.start, center=self.center, ccw=not self.ccw, name=self.name)
        return Edge(self.kind, self.end, self.start, self.controls[::-1], name=self.name)

    def split(self, fraction: float) -> tuple["Edge", "Edge"]:
        """Two edges meeting at ``fraction`` of the arc length."""
        t = float(self.parameters_at_fractions(np.array([fraction]))[0])
        mid = self.point([t])[0]
        if self.kind == "line":
            return Edge("line", self.start, mid, name=self.name), Edge("line", mid, self.end, name=self.name)
        if self.kind == "polyline":
            pts = self._chain()
            cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
            cut = fraction * cum[-1]
            inner_left, inner_right = pts[1:-1][cum[1:-1] < cut], pts[1:-1][cum[1:-1] > cut]
            return (Edge("polyline", self.start, mid, inner_left, name=self.name),
                    Edge("polyline", mid, self.end, inner_right, name=self.name))
        if self.kind == "arc":
            return (Edge("arc", self.start, mid, center=self.center, ccw=self.ccw, name=self.name),
                    Edge("arc", mid, self.end, center=self.center, ccw=self.ccw, name=self.name))
        pts = [self.start, *self.controls, self.end]
        left, right = [pts[0]], [pts[-1]]
        while len(pts) > 1:  # de Casteljau
            pts = [(1 - t) * a + t * b for a, b in zip(pts[:-1], pts[1:])]
            left.append(pts[0])
            right.append(pts[-1])
        right = right[::-1]
        return (Edge(self.kind, left[0], left[-1], np.array(left[1:-1]), name=self.name),
                Edge(self.kind, right[0], right[-1], np.array(right[1:-1]), name=self.name))

    def check(self, where: str) -> None:
        """Raise :class:`InvalidInput` naming ``where`` if the edge is malformed."""
        values = [self.start, self.end, self.controls] + ([self.center] if self.center is not None else [])
        if not all(np.all(np.isfinite(v)) for v in values):
            raise InvalidInput(f"{where}: {self.kind} edge has a non-finite coordinate (NaN or inf)")
        if self.kind not in ("line", "arc", "quadratic", "cubic", "polyline"):
            raise InvalidInput(f"{where}: unknown edge kind {self.kind!r}")
        if self.kind == "arc":
            r0, r1 = np.hypot(*(self.start - self.center)), np.hypot(*(self.end - self.center))
            if r0 <= 0 or abs(r0 - r1) > 1e-6 * max(r0, 1e-3):
                raise InvalidInput(f"{where}: arc end points are not on one circle")
        if not self.length() > 1e-6:
            raise InvalidInput(f"{where}: edge has zero length")


def line(start, end, name: str = "") -> Edge:
    return Edge("line", start, end, name=name)


def arc_through_radius(start, end, radius: float, *, large_arc: bool, ccw: bool, name: str = "") -> Edge:
    """The SVG-style arc: the circle of ``radius`` through both ends, the small or large way
    round, run counter-clockwise (``ccw``) or clockwise from start to end."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    chord = end - start
    half = 0.5 * float(np.hypot(*chord))
    if not (np.isfinite(radius) and radius > 0 and half > 0):
        raise InvalidInput(f"arc{' ' + name if name else ''} needs a positive radius and distinct end points")
    radius = max(radius, half)  # SVG scales up a radius too small to span the chord
    height = np.sqrt(max(radius**2 - half**2, 0.0))
    left = np.array([-chord[1], chord[0]]) / (2 * half)
    side = 1.0 if bool(ccw) != bool(large_arc) else -1.0
    return Edge("arc", start, end, center=0.5 * (start + end) + side * height * left, ccw=bool(ccw), name=name)


def bezier(start, controls, end, name: str = "") -> Edge:
    controls = np.asarray(controls, float).reshape(-1, 2)
    kind = {1: "quadratic", 2: "cubic"}.get(len(controls))
    if kind is None:
        raise InvalidInput(f"a Bezier edge takes 1 or 2 control points, got {len(controls)}")
    return Edge(kind, start, end, controls, name=name)
