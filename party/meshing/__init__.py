"""Meshing: turning flat cloth (a rectangle now, sewing-pattern panels later) into the paper's
elastic net: nodes, warp/weft elements and triangles, in the flat pattern's own coordinates."""

from .net import ClothNet, ElementKind, rectangular_net

__all__ = ["ClothNet", "ElementKind", "rectangular_net"]
