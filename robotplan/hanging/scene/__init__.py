"""Hanging's scene layer: the mug and hook solids of a scene, the ranges scenes are drawn from."""
