"""Case 8: mesh convergence. The catenary, the cantilever test and the Cusick drape at three
resolutions, each r times as fine as the last (r = 2; sqrt(2) for the Cusick drape, whose
coarsest mesh must still have nodes across the hanging skirt): the answers must converge
(each change smaller than the one before), and the observed order p is reported,

    p = log(|f1 - f2| / |f2 - f3|) / log(r)       (f1 coarsest)

or, where the exact answer is known, log(e2 / e3) / log(r) from the errors of the two finest.
"""

from __future__ import annotations

import math

from ..errors import SimulationUnstable
from ..fabric import Fabric, fabric_by_name
from . import cantilever, catenary, cusick
from .checks import CaseResult, Check

NAME = "convergence"


def run_case(fabric: Fabric | None, solver: str, *, quick: bool = False, out=None) -> CaseResult:
    fabric = fabric or fabric_by_name("cotton")
    result = CaseResult(NAME)

    for part in (_catenary, _cantilever, _cusick):
        try:
            part(result, fabric, solver, quick)
        except SimulationUnstable as problem:
            result.checks.append(Check.decision(NAME, f"came to rest ({problem})", False, True))
    return result


def _catenary(result: CaseResult, fabric: Fabric, solver: str, quick: bool) -> None:
    spacing = 0.04 if quick else 0.02
    deviation = [catenary.strip_deviation(fabric, solver, spacing / 2**k) for k in range(3)]
    _add(result, "catenary deviation / span", deviation, 2.0, exact=0.0)


def _cantilever(result: CaseResult, fabric: Fabric, solver: str, quick: bool) -> None:
    if fabric.bending_rigidity > 0.0:
        segments = 8 if quick else 15
        reference = cantilever.reference_bending_length(fabric)
        lengths = [0.5 * cantilever.bending_length_test(fabric, solver, segments * 2**k)[0] for k in range(3)]
        _add(result, f"{fabric.name} cantilever bending length [mm]", [1000 * c for c in lengths], 2.0,
             exact=1000 * reference)


def _cusick(result: CaseResult, fabric: Fabric, solver: str, quick: bool) -> None:
    spacing = 0.0212 if quick else 0.015  # down to case 6's 7.5 mm (5.3 mm took over an hour to settle)
    dc = [100.0 * cusick.drape_test(fabric, solver, spacing / math.sqrt(2) ** k).coefficient for k in range(3)]
    _add(result, f"{fabric.name} Cusick DC [%]", dc, math.sqrt(2), exact=None)


def _add(result: CaseResult, quantity: str, values: list[float], ratio: float, *, exact: float | None) -> None:
    changes = [abs(values[1] - values[0]), abs(values[2] - values[1])]
    result.details[quantity] = {"values": values, "refinement": ratio, "exact": exact}
    result.checks.append(Check.decision(NAME, f"{quantity}: converges ({', '.join(f'{v:.4g}' for v in values)})",
                                        changes[1] < changes[0], True))
    errors = [abs(v - exact) for v in values[1:]] if exact is not None else changes
    order = math.log(errors[0] / errors[1]) / math.log(ratio) if min(errors) > 0 else math.nan
    result.checks.append(Check.report(NAME, f"{quantity}: observed order", order))
