"""Case 8: mesh convergence. The catenary, the cantilever test and the Cusick drape at three
resolutions, each twice as fine as the last: the answers must converge (each change smaller
than the one before), and the observed order p is reported,

    p = log2(|f1 - f2| / |f2 - f3|)       (f1 coarsest)

or, where the exact answer is known, log2(e1 / e2) from the errors of the two finest.
"""

from __future__ import annotations

import math

from ..fabric import Fabric, fabric_by_name
from . import cantilever, catenary, cusick
from .checks import CaseResult, Check

NAME = "convergence"
LEVELS = {"quick": (1, 2, 4), "default": (1, 2, 4)}  # refinement factors


def run_case(fabric: Fabric | None, solver: str, *, quick: bool = False, out=None) -> CaseResult:
    fabric = fabric or fabric_by_name("cotton")
    result = CaseResult(NAME)
    levels = LEVELS["quick" if quick else "default"]

    spacing = 0.04 if quick else 0.02
    deviation = [catenary.strip_deviation(fabric, solver, spacing / k) for k in levels]
    _add(result, "catenary deviation / span", deviation, exact=0.0)

    if fabric.bending_rigidity > 0.0:
        segments = 8 if quick else 15
        reference = cantilever.reference_bending_length(fabric)
        lengths = [0.5 * cantilever.bending_length_test(fabric, solver, segments * k)[0] for k in levels]
        _add(result, f"{fabric.name} cantilever bending length [mm]", [1000 * c for c in lengths],
             exact=1000 * reference)

    spacing = 0.03 if quick else 0.02
    dc = [100.0 * cusick.drape_test(fabric, solver, spacing / k).coefficient for k in levels]
    _add(result, f"{fabric.name} Cusick DC [%]", dc, exact=None)
    return result


def _add(result: CaseResult, quantity: str, values: list[float], *, exact: float | None) -> None:
    changes = [abs(values[1] - values[0]), abs(values[2] - values[1])]
    result.details[quantity] = {"values": values, "exact": exact}
    result.checks.append(Check.decision(NAME, f"{quantity}: converges ({', '.join(f'{v:.4g}' for v in values)})",
                                        changes[1] < changes[0], True))
    if exact is not None:
        errors = [abs(v - exact) for v in values[1:]]
        order = math.log2(errors[0] / errors[1]) if errors[1] > 0 and errors[0] > 0 else math.nan
    else:
        order = math.log2(changes[0] / changes[1]) if changes[1] > 0 and changes[0] > 0 else math.nan
    result.checks.append(Check.report(NAME, f"{quantity}: observed order", order))
