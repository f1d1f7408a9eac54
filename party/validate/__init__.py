"""Validation against known answers and measured cloth (``party validate``).

Each case is a scene with a reference: analytic (oscillation periods, the catenary,
restitution, the friction cone), numerical (the heavy elastica of the cantilever test) or
measured (Cusick drape of real fabrics). :func:`run_validation` runs them and reports each
quantity against its reference and tolerance.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

from ..errors import InvalidInput, SimulationUnstable
from ..fabric import Fabric
from . import cantilever, catenary, convergence, cusick, friction, oscillation, restitution
from .checks import CaseResult, Check

CASES: dict[str, tuple[Callable[..., CaseResult], str]] = {
    "oscillation": (oscillation.run_case, "spring-mass and strip periods against 2 pi sqrt(m/k) and 4 L / c"),
    "catenary": (catenary.run_case, "chain and strip hung from two pins against the elastic catenary"),
    "cantilever": (cantilever.run_case, "ASTM D1388 bending length and the heavy elastica"),
    "friction": (friction.run_case, "patch on an inclined plane: the friction cone and g (sin - mu cos)"),
    "restitution": (restitution.run_case, "node bouncing on a plane leaves with sigma times its speed"),
    "cusick": (cusick.run_case, "BS 5058 drape coefficient and folds, every library fabric (or the one given)"),
    "cusick-measured": (cusick.run_measured, "Cusick drape of three measured fabrics against their measured DC and folds"),
    "convergence": (convergence.run_case, "catenary, cantilever and Cusick at three resolutions: observed order"),
}


def case_names(name: str | None) -> list[str]:
    """The cases ``--case`` selects (all of them when None)."""
    if name is None:
        return list(CASES)
    if name not in CASES:
        raise InvalidInput(f"unknown validation case {name!r}; known: {', '.join(CASES)}")
    return [name]


def run_validation(names: list[str], fabric: Fabric | None, solver: str, out: Path | None, *, quick: bool = False,
                   on_case: Callable[[str], None] | None = None, kept: dict[str, CaseResult] | None = None,
                   on_result: Callable[[list[CaseResult]], None] | None = None) -> list[CaseResult]:
    """Run the cases ``names`` with ``solver`` and ``fabric`` (None: cotton, and every library
    fabric for the Cusick cases), writing plots into ``out``; ``on_case(name)`` is called as
    each starts, ``on_result(results so far)`` as each ends. A case in ``kept`` (by name: the
    results of an earlier run with the same settings) is taken from there instead of run."""
    from ..fabric import fabric_by_name

    results = []
    for name in names:
        if kept and name in kept:
            results.append(kept[name])
            continue
        if on_case is not None:
            on_case(name)
        given = fabric if fabric is not None or name in LIBRARY_CASES else fabric_by_name(DEFAULT_FABRIC)
        start = time.perf_counter()
        try:
            result = CASES[name][0](given, solver, quick=quick, out=out)
        except SimulationUnstable as problem:
            result = CaseResult(name, [Check.decision(name, f"came to rest ({problem})", False, True)])
        result.wall_seconds = time.perf_counter() - start
        results.append(result)
        if on_result is not None:
            on_result(results)
    return results


LIBRARY_CASES = ("cusick", "cusick-measured", "convergence")
"""Cases that run every library fabric (or their own) when no fabric is given."""

DEFAULT_FABRIC = "cotton"
"""The fabric of the single-fabric cases when none is given."""

__all__ = ["CASES", "CaseResult", "Check", "DEFAULT_FABRIC", "case_names", "run_validation"]
