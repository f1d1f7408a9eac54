"""Scenes: the paper's experiments and benchmark set-ups, each a short file, run by
:func:`party.scenes.runner.run_scene`."""

from .registry import SCENES, scene_by_name

__all__ = ["SCENES", "scene_by_name"]
