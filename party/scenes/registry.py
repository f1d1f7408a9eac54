"""Scenes by name: each scene's build function and its settings."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..errors import InvalidInput
from . import dress, rod_wind, sphere_drop


@dataclass(frozen=True)
class SceneEntry:
    """A scene ``party run`` knows: ``build(settings, *, device, out, resume, progress)`` makes
    it from a ``settings`` instance (a frozen dataclass whose fields are its options)."""

    build: Callable
    settings: type
    description: str


SCENES: dict[str, SceneEntry] = {
    "rod-wind": SceneEntry(rod_wind.build, rod_wind.Settings,
                           "Experiment 1: cloth over a rod in a cross wind (figure 11)"),
    "dress": SceneEntry(dress.build, dress.Settings,
                        "Experiment 2: a one-piece dress with sleeves on the dress form (figures 12-14)"),
    "sphere-drop": SceneEntry(sphere_drop.build, sphere_drop.Settings,
                              "Benchmark: a 1 m square cloth of N x N nodes dropped on a sphere"),
}


def scene_by_name(name: str) -> SceneEntry:
    try:
        return SCENES[name]
    except KeyError:
        raise InvalidInput(f"unknown scene {name!r}; known: {', '.join(sorted(SCENES))}") from None
