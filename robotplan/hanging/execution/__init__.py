"""Hanging's execution layer: the pybullet world a mug is dropped in."""
