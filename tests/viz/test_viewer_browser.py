"""A written playback page in a real browser: headless Chromium loads it, the time slider
moves, the bodies move with it, no JavaScript error. Skipped where no Chromium is installed
(the README says how to install it)."""

import json
import re
import shutil
import subprocess

import numpy as np
import pytest

from robotplan.pushing.execution.execute import execute_push, reach_substeps
from robotplan.scene.task import load_task
from robotplan.viz.viewer import Layer, write_playback
from tests.conftest import TASKS

BROWSER = next((b for b in ("chromium", "chromium-browser", "google-chrome")
                if shutil.which(b)), None)
pytestmark = pytest.mark.skipif(BROWSER is None, reason="no Chromium installed")

FPS = 12.0
# Moves the slider of the MeshCat "Animations" folder to every frame and records where the
# named nodes are and whether they are visible; collects every JavaScript error.
HARNESS = """<script>
window.__errors = [];
window.addEventListener('error', e => window.__errors.push(String(e.message)));
window.addEventListener('unhandledrejection', e => window.__errors.push(String(e.reason)));
setTimeout(() => {
  const out = {errors: window.__errors, samples: {}};
  try {
    const slider = viewer.animator.time_scrubber;
    for (const path of PATHS) {
      const node = viewer.scene_tree.find(path.split('/'));
      out.samples[path] = [];
      for (let k = 0; k <= FRAMES; k++) {
        slider.setValue(k / FPS);
        node.object.updateMatrixWorld(true);
        let shown = true;
        for (let o = node.object; o; o = o.parent) shown = shown && o.visible;
        const e = node.object.matrixWorld.elements;
        out.samples[path].push([e[12], e[13], e[14], shown]);
      }
    }
  } catch (e) { out.errors.push('harness: ' + e); }
  const pre = document.createElement('pre');
  pre.id = 'robotplan-result';
  pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
}, 3000);
</script>"""


def open_in_browser(page, paths: list[str], frames: int, tmp_path) -> dict:
    """Load ``page`` in headless Chromium with the harness; its report."""
    script = (HARNESS.replace("PATHS", json.dumps(paths)).replace("FRAMES", str(frames))
              .replace("FPS", str(FPS)))
    probe = tmp_path / "probe.html"
    probe.write_text(page.read_text().replace("</body>", script + "</body>"))
    res = subprocess.run([BROWSER, "--headless", "--no-sandbox", "--disable-gpu",
                          "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                          f"--user-data-dir={tmp_path / 'profile'}",
                          "--virtual-time-budget=20000", "--dump-dom", probe.as_uri()],
                         capture_output=True, text=True, timeout=120)
    found = re.search(r'<pre id="robotplan-result">(.*?)</pre>', res.stdout, re.S)
    assert found, f"no report from the page: {res.stderr[-2000:]}"
    return json.loads(found.group(1).replace("&quot;", '"').replace("&amp;", "&"))


def test_the_playback_moves_with_the_slider_and_transit_is_a_motion(tmp_path):
    """A pusher that moves 0.45 m in one free step (as a planned transit may) is drawn
    moving smoothly over the slowed steps pybullet executed, the box moves when pushed, the
    ghosted plan layer disappears when the next plan takes over."""
    task = load_task(TASKS / "box_push.yaml")
    scene = task.scene
    transit = np.array([[-0.28, 0.10], [-0.28, -0.35]])  # a long free move
    approach = np.linspace([-0.28, -0.35], [-0.20, 0.0], 8)
    push = np.linspace([-0.20, 0.0], [0.30, 0.05], 20)
    q = np.vstack([transit, approach[1:], push[1:]])
    free = np.array([True] + [False] * (len(q) - 2))
    substeps = reach_substeps(q, ~free)
    ex = execute_push(task, q, substeps=substeps)
    half = float(ex.times[len(ex.times) // 2])
    page = tmp_path / "playback.html"
    write_playback(scene, page, [
        Layer("plan", ex.times, {"pusher": q}, shown=(0.0, half)),
        Layer("executed", ex.times, {"box": ex.object_poses, "pusher": ex.pusher_positions},
              ghost=False)])
    frames = int(np.ceil(ex.times[-1] * FPS))
    report = open_in_browser(page, ["executed/pusher", "executed/box", "plan/pusher"],
                             frames, tmp_path)
    assert report["errors"] == []
    pusher = np.array([s[:3] for s in report["samples"]["executed/pusher"]])
    box = np.array([s[:3] for s in report["samples"]["executed/box"]])
    assert np.linalg.norm(pusher[-1, :2] - pusher[0, :2]) > 0.3  # the bodies moved
    assert np.linalg.norm(box[-1, :2] - box[0, :2]) > 0.2
    assert box[-1, 0] == pytest.approx(ex.final_pose[0], abs=0.01)  # where pybullet left it
    steps = np.linalg.norm(np.diff(pusher[:, :2], axis=0), axis=1)
    assert steps.max() < 0.05, f"the pusher jumps {steps.max():.3f} m in one frame"
    shown = [s[3] for s in report["samples"]["plan/pusher"]]
    assert shown[0] and not shown[-1]  # the plan layer hides when the next plan starts
