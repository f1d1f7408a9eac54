"""The model stage: a builder assembles an immutable :class:`Model`; a :class:`State` holds
what changes each step; a :class:`Control` holds what the scene drives (wind, handles)."""

from .builder import ClothRange, ModelBuilder
from .model import HostArrays, Model
from .state import Control, State

__all__ = ["ClothRange", "Control", "HostArrays", "Model", "ModelBuilder", "State"]
