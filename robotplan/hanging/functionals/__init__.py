"""Hanging's functionals layer: H_hang, H_coll in 3D and H_thread."""
