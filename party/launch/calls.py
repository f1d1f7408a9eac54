"""What identifies a kernel launch's packed arguments, so that a repeated call can replay the
launch recorded for it (:meth:`party.launch.Launcher.launch`)."""

from __future__ import annotations

from typing import Any, Sequence

import warp as wp

_SCALARS = (bool, int, float)


def call_key(kernel: Any, dim: Any, inputs: Sequence[Any], outputs: Sequence[Any], device: Any) -> tuple | None:
    """The kernel, its dimensions, its device and what is packed of each argument; None where
    an argument is of a kind not covered (the call is then launched plainly)."""
    parts: list[Any] = [kernel, dim, device.alias]
    for arg in (*inputs, *outputs):
        if type(arg) is wp.array:
            parts.append(id(arg))  # the record holds on to the array, so no other object can take its id
            continue
        part = value_key(arg)
        if part is None:
            return None
        parts.append(part)
    return tuple(parts)


def value_key(arg: Any) -> tuple | None:
    """What a recorded launch packs of an argument: an array's address, shape and strides, a
    scalar's, vector's or matrix's value, a struct's fields (so a struct whose fields were
    changed is recorded anew); None for other kinds."""
    kind = type(arg)
    if kind in _SCALARS:
        return (kind, arg)
    if isinstance(arg, wp.array):
        return (arg.ptr, arg.shape, arg.strides)
    if hasattr(arg, "_length_"):  # Warp's vector and matrix values
        return (kind, tuple(arg))
    fields = getattr(getattr(arg, "_cls", None), "vars", None)  # a Warp struct
    if fields is None:
        return None
    parts = [kind]
    for name in fields:
        value = getattr(arg, name)
        part = ("unset",) if value is None else value_key(value)
        if part is None:
            return None
        parts.append(part)
    return tuple(parts)
