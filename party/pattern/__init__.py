"""Sewing patterns: panels, edges, grain lines, seams, placement; readers for our JSON format,
GarmentCode's specifications and DXF-AAMA."""

from .edges import Edge, arc_through_radius, bezier, line
from .load import load_pattern
from .pattern import EdgeRef, Panel, Pattern, Placement, Seam, euler_xyz_degrees

__all__ = ["Edge", "EdgeRef", "Panel", "Pattern", "Placement", "Seam", "arc_through_radius", "bezier",
           "euler_xyz_degrees", "line", "load_pattern"]
