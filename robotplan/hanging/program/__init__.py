"""Hanging's program layer: the Drake program over the mug's pose."""
