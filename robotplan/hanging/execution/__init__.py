"""Hanging's execution layer: the worlds a mug is dropped in (pybullet, MuJoCo) and the drop
test they share."""
