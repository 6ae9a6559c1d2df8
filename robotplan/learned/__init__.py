"""Learned functionals: pushing dynamics F_flow / F (paper §5.1) — data, model, training."""
