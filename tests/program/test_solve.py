"""robotplan.program.solve: what a skeleton's solve checks before any program is built."""

import numpy as np
import pytest

from robotplan.program.settings import DEFAULT_SETTINGS
from robotplan.program.skeleton import Phase, Skeleton, space_for
from robotplan.program.solve import solve_skeleton
from robotplan.scene import load_scene
from tests.conftest import TASKS


def test_a_guess_of_another_length_is_refused_before_any_program_is_built():
    """A warm-start guess whose states do not fit the skeleton's steps: a clear error
    instead of a failed size check inside Drake."""
    scene = load_scene(TASKS / "box_push.yaml")
    skeleton = Skeleton((Phase("reach", "pusher", "box", 0), Phase("push", "pusher", "box", 0)))
    space = space_for(scene)
    with pytest.raises(ValueError, match="states"):
        solve_skeleton(scene, skeleton, None, space, DEFAULT_SETTINGS,
                       guess={"q_obj": np.zeros((2 * space.steps_per_phase + 5, 3))})
