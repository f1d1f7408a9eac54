"""How many CPU threads party's launches use."""

from __future__ import annotations

import os

CORES = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
"""The cores this process may use."""


def thread_count() -> int:
    """Threads item-wise launches use on the CPU: ``$PARTY_THREADS`` (a whole number from 1),
    else :data:`CORES`."""
    given = os.environ.get("PARTY_THREADS")
    if given is None or given.strip() == "":
        return max(CORES, 1)
    try:
        threads = int(given)
    except ValueError:
        threads = 0
    if threads < 1:
        from ..errors import InvalidInput

        raise InvalidInput(f"PARTY_THREADS must be a whole number of threads from 1, got {given!r}")
    return threads
