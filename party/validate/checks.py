"""What a validation case reports: one :class:`Check` per quantity compared with its
reference, gathered in a :class:`CaseResult` with the case's pictures and extra figures."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path


@dataclass(frozen=True)
class Check:
    """One simulated quantity against its reference.

    Attributes:
        case: The case's name.
        quantity: What is compared, with its unit, e.g. ``"period [s]"``.
        simulated: The simulated value.
        reference: The reference value (analytic, numerical or measured); NaN where the case
            only reports (no reference exists, e.g. the drape coefficient of a library fabric).
        error: The error in the tolerance's terms (relative, in degrees, in DC points, ...).
        tolerance: The largest error that passes, in the same terms; NaN where only reported.
        error_kind: How ``error`` is measured, e.g. ``"relative"`` or ``"fraction of span"``.
        passed: Whether the error is within the tolerance (always True where only reported).
    """

    case: str
    quantity: str
    simulated: float
    reference: float
    error: float
    tolerance: float
    error_kind: str
    passed: bool

    @classmethod
    def relative(cls, case: str, quantity: str, simulated: float, reference: float, tolerance: float) -> "Check":
        """|simulated - reference| / |reference| against ``tolerance``."""
        error = abs(simulated - reference) / abs(reference) if reference else math.inf
        return cls(case, quantity, float(simulated), float(reference), float(error), tolerance, "relative",
                   bool(error <= tolerance))

    @classmethod
    def absolute(cls, case: str, quantity: str, simulated: float, reference: float, tolerance: float,
                 error_kind: str) -> "Check":
        """|simulated - reference| against ``tolerance`` (in the quantity's own unit)."""
        error = abs(simulated - reference)
        return cls(case, quantity, float(simulated), float(reference), float(error), tolerance, error_kind,
                   bool(error <= tolerance))

    @classmethod
    def bound(cls, case: str, quantity: str, error: float, tolerance: float, error_kind: str,
              simulated: float = math.nan, reference: float = math.nan) -> "Check":
        """An error computed by the case (a largest deviation, say) against ``tolerance``."""
        return cls(case, quantity, float(simulated), float(reference), float(error), tolerance, error_kind,
                   bool(error <= tolerance))

    @classmethod
    def decision(cls, case: str, quantity: str, simulated: bool, expected: bool) -> "Check":
        """A yes/no outcome (1/0) that must equal the expected one."""
        return cls(case, quantity, float(simulated), float(expected), float(simulated != expected), 0.0,
                   "wrong decision", bool(simulated == expected))

    @classmethod
    def report(cls, case: str, quantity: str, simulated: float) -> "Check":
        """A value reported without a reference."""
        return cls(case, quantity, float(simulated), math.nan, math.nan, math.nan, "reported", True)

    def to_dict(self) -> dict:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}


@dataclass
class CaseResult:
    """A case's checks, the pictures it wrote and its own figures (curves, settings)."""

    name: str
    checks: list[Check] = field(default_factory=list)
    plots: list[Path] = field(default_factory=list)
    details: dict = field(default_factory=dict)
    wall_seconds: float = 0.0

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)
