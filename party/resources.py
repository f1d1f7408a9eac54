"""What a run will need against what the machine has, judged before the work starts: a garment
too fine for the memory is refused with the spacing that would fit, not killed minutes later."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

from .errors import InvalidInput


@dataclass(frozen=True)
class Footprint:
    """Peak memory of a kind of run: ``base`` [bytes] (the interpreter, Warp, NumPy, the body)
    plus ``per_node`` [bytes] for each node of the cloth."""

    base: float
    per_node: float

    def bytes(self, nodes: int) -> float:
        return self.base + self.per_node * nodes


DRAPE_FOOTPRINT = Footprint(base=600e6, per_node=20e3)
"""``party drape``'s peak resident memory, an upper bound fitted to GarmentCode's jumpsuit on
``mean_all`` from 40 mm down to 12 mm spacing (``benchmarks/drape_memory.py``): the Warp
arrays of the two models (sewing and draping), their collision pipelines and the set-up's
sparse matrices."""

HEADROOM = 0.9
"""Share of the available memory a run may plan to use."""


def available_memory() -> float:
    """Memory [bytes] this process may still take: the system's available memory, or the
    control group's limit less its use, or ``$PARTY_MAX_MEMORY`` (bytes, or with a suffix K, M
    or G: ``8G``), whichever is lowest."""
    free = _given_limit()
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                free = float(line.split()[1]) * 1024.0
    except OSError:
        pass
    if not math.isfinite(free) and hasattr(os, "sysconf"):
        try:
            free = float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_AVPHYS_PAGES"))
        except (OSError, ValueError):
            pass
    for limit_file, used_file in (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                                  ("/sys/fs/cgroup/memory/memory.limit_in_bytes",
                                   "/sys/fs/cgroup/memory/memory.usage_in_bytes")):
        try:
            limit = Path(limit_file).read_text().strip()
            used = float(Path(used_file).read_text().strip())
        except (OSError, ValueError):
            continue
        if limit.isdigit() and float(limit) < 1e18:
            free = min(free, float(limit) - used)
    return free


def _given_limit() -> float:
    """``$PARTY_MAX_MEMORY`` in bytes (infinite where unset)."""
    given = os.environ.get("PARTY_MAX_MEMORY", "").strip()
    if not given:
        return math.inf
    scale = {"K": 1e3, "M": 1e6, "G": 1e9}.get(given[-1].upper(), 1.0)
    try:
        value = float(given[:-1] if scale != 1.0 else given) * scale
    except ValueError:
        value = math.nan
    if not value > 0 or not math.isfinite(value):
        raise InvalidInput(f"PARTY_MAX_MEMORY must be a positive size in bytes (or with K, M or G: 8G), got {given!r}")
    return value


def check_memory(footprint: Footprint, nodes: int, spacing: float, free: float | None = None) -> None:
    """Refuse a garment of about ``nodes`` nodes at ``spacing`` [m] whose run would not fit in
    ``free`` [bytes] (default: :func:`available_memory`), naming the spacing that would (nodes
    go as 1 / spacing^2)."""
    free = HEADROOM * (available_memory() if free is None else free)
    needed = footprint.bytes(nodes)
    if needed <= free:
        return
    room = (free - footprint.base) / footprint.per_node
    if room <= 0:
        raise InvalidInput(f"this machine has {free / 1e9:.2g} GB of memory free, too little for a drape "
                           f"(at least {footprint.base / 1e9:.2g} GB)")
    fits = spacing * math.sqrt(nodes / room)
    raise InvalidInput(f"about {nodes:,} nodes at --spacing-mm {spacing * 1000:g} would need about "
                       f"{needed / 1e9:.2g} GB of memory and this machine has {free / 1e9:.2g} GB free; use "
                       f"--spacing-mm {math.ceil(fits * 1000):g} or more")


def check_time_limit(seconds: float) -> float:
    """``seconds``, the wall time a drape may take, or :class:`InvalidInput` where it is not a
    finite positive number."""
    if not (math.isfinite(seconds) and seconds > 0):
        raise InvalidInput(f"--time-limit must be a positive number of seconds, got {seconds:g}")
    return seconds
