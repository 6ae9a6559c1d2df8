"""Fixtures of the drop tests in both worlds."""

import pytest


@pytest.fixture(scope="session")
def mesh_parts():
    """A mesh mug with a square handle and a mesh hook of a square rod
    (``tasks/meshes/hang/``), read once: their SDF lattices take seconds to sample."""
    from robotplan.geometry.meshes import read_mesh
    from robotplan.sdf.mesh_solids import MeshHook, MeshMug
    from tests.conftest import TASKS

    folder = TASKS / "meshes" / "hang"
    mug, hook = folder / "mug_square_handle.stl", folder / "hook_square_rod.stl"
    return MeshMug(read_mesh(mug), mug), MeshHook(read_mesh(hook), hook)
