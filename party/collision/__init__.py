"""Collision (paper section 6): detection along each node's step with axis interval lists and
a thickness, and velocity responses against bodies (eqs. 8-12) and cloth (eqs. 13-14), chained
through layers (figure 10)."""

from .intervals import AxisIntervalLists
from .pipeline import CollisionPipeline, CollisionSettings
from . import presets

__all__ = ["AxisIntervalLists", "CollisionPipeline", "CollisionSettings", "presets"]
