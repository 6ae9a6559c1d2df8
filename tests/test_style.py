"""The code stays ruff-clean (the rules are in pyproject.toml)."""

import shutil
import subprocess
import sys

import pytest

from tests.conftest import ROOT


def test_ruff_clean():
    ruff = shutil.which("ruff") or str(ROOT / ".venv" / "bin" / "ruff")
    if not shutil.which(ruff):
        pytest.skip("ruff is not installed")
    res = subprocess.run([ruff, "check", "robotplan", "tests", "tasks"], cwd=ROOT,
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr


def test_package_imports_without_pybullet_banner():
    res = subprocess.run([sys.executable, "-c", "import robotplan.scene.robots as r; "
                          "r.load_robot_model('iiwa').tip_position((0,) * 7, (0, 0, 0, 0))"],
                         cwd=ROOT, capture_output=True, text=True)
    assert res.returncode == 0 and res.stdout == "" and res.stderr == ""
