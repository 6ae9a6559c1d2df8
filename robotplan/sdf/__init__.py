"""Signed-distance fields: exact 2D footprints and 3D shapes, and the workspace grid X_h."""

from robotplan.sdf.closed_form import polygon_sdf
from robotplan.sdf.grid import Workspace
from robotplan.sdf.shapes2d import Box, Circle, LShape, Polygon, Shape2D
from robotplan.sdf.shapes3d import Box3D, Capsule, Cylinder, Extrusion, Mesh, Shape3D, Sphere

__all__ = [
    "Box",
    "Box3D",
    "Capsule",
    "Circle",
    "Cylinder",
    "Extrusion",
    "LShape",
    "Mesh",
    "Polygon",
    "Shape2D",
    "Shape3D",
    "Sphere",
    "Workspace",
    "polygon_sdf",
]
