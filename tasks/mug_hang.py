"""A mug hung on a hook (paper §7.1): H_hang and H_coll optimised over the mug's pose,
restarted from random poses, the pose then checked by dropping the mug in pybullet; closed
loop (the default) goes on searching while the mug falls from the poses found.

``python tasks/mug_hang.py [--fast] [--open-loop] [--out DIR]`` (``--fast``: at most 3
optimisations; ``--open-loop``: drop the first pose found only, the paper's protocol)
"""

from task_cli import HERE, arguments, run_hang

if __name__ == "__main__":
    run_hang(HERE / "mug_hang.yaml", arguments(__doc__.splitlines()[0]), __file__)
