"""What a simulation carries from one step to the next, saved with a run's checkpoint so that a
resumed run goes on bit for bit as the run it continues would have.

A step reads more than the State: the solver and the objects it owns keep arrays and counters
from step to step (the implicit solver's correction, the collision pipeline's contact faces and
the body candidates its planes start from, the crossing guard's last checked positions, the air's
shielding). Each object names what it carries in an attribute ``carried``: attribute paths
(dotted where they lead into a Warp struct) of Warp arrays and numbers. :func:`memory` collects
them from the solver (or a State) and every party object it holds, by path; :func:`restore` puts
them back into objects built afresh for the same scene. Everything else a solver holds is either
fixed by the model and its settings, or rewritten before it is read in a step.

Search structures are not carried (a BVH's shape depends on the boxes it was first built
from): a resumed run calls :func:`forget` after :func:`restore` (each object's
``forget_search``, which asks for a new search at the next step) and searches afresh. What a
step computes does not depend on what a search listed: cloth contacts are kept in order of
distance, then triangle, the body's earliest contact wins, and the crossing guard's answer is
that of testing every pair. So the resumed run goes on bit for bit, and the run it continues
keeps its searches across checkpoints.
"""

from __future__ import annotations

from typing import Any, Iterator

import numpy as np
import warp as wp

from ..errors import InvalidInput
from ..model import Model


def memory(root: Any) -> dict[str, np.ndarray]:
    """What ``root`` and the party objects it holds carry (see the module docstring): each
    Warp array as a NumPy copy and each number, by path from ``root``."""
    saved = {}
    for path, value in _carried(root):
        saved[path] = value.numpy().copy() if isinstance(value, wp.array) else np.asarray(value)
    return saved


def restore(root: Any, saved: dict[str, np.ndarray]) -> None:
    """Put :func:`memory`'s ``saved`` back into ``root``, built afresh for the same scene;
    :class:`InvalidInput` where an entry is missing or does not fit (another kind of run)."""
    for path, value in _carried(root):
        if path not in saved:
            raise InvalidInput(f"the checkpoint lacks {path}; it belongs to another kind of run (remove it or "
                               "drop --resume)")
        data = saved[path]
        if isinstance(value, wp.array):
            if tuple(value.shape) != tuple(data.shape[:value.ndim]) or value.numpy().dtype != data.dtype:
                raise InvalidInput(f"the checkpoint's {path} {data.shape} does not fit this run's "
                                   f"{tuple(value.shape)}; remove it or drop --resume")
            value.assign(data)
        else:
            owner, name = _owner(root, path)
            setattr(owner, name, type(value)(data.item()))


def forget(root: Any) -> None:
    """Drop the search structures of ``root`` and the objects it holds (each one's
    ``forget_search``)."""
    for _, obj in _objects(root):
        if hasattr(obj, "forget_search"):
            obj.forget_search()


def _carried(root: Any) -> Iterator[tuple[str, Any]]:
    """(path, value) of everything the objects under ``root`` name in ``carried``."""
    for prefix, obj in _objects(root):
        for name in getattr(obj, "carried", ()):
            value = obj
            for part in name.split("."):
                value = getattr(value, part)
            yield prefix + name, value


def _objects(root: Any) -> Iterator[tuple[str, Any]]:
    """(path prefix, object) of ``root`` and the party objects reachable through attributes
    (the Model aside), each once, in a fixed order."""
    seen: set[int] = set()
    queue = [("", root)]
    while queue:
        prefix, obj = queue.pop(0)
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        yield prefix, obj
        for name, child in vars(obj).items():
            if _is_party_object(child):
                queue.append((f"{prefix}{name}.", child))


def _owner(root: Any, path: str) -> tuple[Any, str]:
    *parents, name = path.split(".")
    owner = root
    for part in parents:
        owner = getattr(owner, part)
    return owner, name


def _is_party_object(value: Any) -> bool:
    return type(value).__module__.startswith("party.") and hasattr(value, "__dict__") and not isinstance(value, Model)
