"""Hanging's viz layer: the MeshCat page and the PNG pictures of a mug and a hook."""
