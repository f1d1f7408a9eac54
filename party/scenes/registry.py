"""Scenes by name."""

from __future__ import annotations

from typing import Callable

from ..errors import InvalidInput
from . import dress, rod_wind, sphere_drop

SCENES: dict[str, tuple[Callable, str]] = {
    "rod-wind": (rod_wind.build, "Experiment 1: cloth over a rod in a cross wind (figure 11)"),
    "dress": (dress.build, "Experiment 2: a one-piece dress with sleeves on the dress form (figures 12-14)"),
    "sphere-drop": (sphere_drop.build, "Benchmark: a 1 m square cloth of N x N nodes dropped on a sphere"),
}


def scene_by_name(name: str) -> Callable:
    try:
        return SCENES[name][0]
    except KeyError:
        raise InvalidInput(f"unknown scene {name!r}; known: {', '.join(sorted(SCENES))}") from None
