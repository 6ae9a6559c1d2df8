"""A regular (non-editable) install finds its robots, skeletons and learned weights inside
the package and solves box_push from another directory (slow: a fresh venv)."""

import json
import shutil
import subprocess
import sys

import pytest

from tests.conftest import ROOT, TASKS


@pytest.mark.slow
def test_a_regular_install_solves_box_push_from_elsewhere(tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    # the dependencies from this environment (its site-packages on the path, its .pth files
    # and so its editable robotplan not read): robotplan itself only from the install
    site = next(p for p in sys.path if p.endswith("site-packages"))
    (next((venv / "lib").glob("python*")) / "site-packages" / "deps.pth").write_text(site)
    # the wheel is built here (this environment's setuptools, no download), as `pip install .`
    # builds it, and installed there without its dependencies
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps",
                    "--disable-pip-version-check", "--no-build-isolation", "-w", str(wheels),
                    str(ROOT)], check=True, cwd=tmp_path)
    (wheel,) = wheels.glob("robotplan-*.whl")
    subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "install", "-q", "--no-deps",
                    "--disable-pip-version-check", str(wheel)], check=True, cwd=tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    shutil.copy(TASKS / "box_push.yaml", elsewhere)
    res = subprocess.run([str(venv / "bin" / "robotplan"), "solve", "box_push.yaml", "--out",
                          "out"], cwd=elsewhere, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-2000:]
    doc = json.loads((elsewhere / "out" / "result.json").read_text())
    assert doc["execution"]["coverage"] >= 0.95
    where = subprocess.run([str(venv / "bin" / "python"), "-c", "import robotplan.base."
                            "resources as r; print(r.data_root())"], cwd=elsewhere,
                           capture_output=True, text=True, check=True).stdout.strip()
    assert where.endswith("robotplan/_data") and str(ROOT) not in where
