"""A mug hung on a hook, both given as mesh files: the handle's opening and the hook's arm
found from their geometry, H_hang reading their SDFs (cached lattices of the meshes), the
pose checked by dropping the meshes in pybullet; closed loop as tasks/mug_hang.py.

``python tasks/mesh_mug_hang.py [--fast] [--open-loop] [--out DIR]`` (``--fast``: at most 3
optimisations; ``--open-loop``: drop the first pose found only, the paper's protocol)
"""

from task_cli import HERE, arguments, run_hang

if __name__ == "__main__":
    run_hang(HERE / "mesh_mug_hang.yaml", arguments(__doc__.splitlines()[0]), __file__)
