"""Install-time steps that pyproject.toml cannot declare.

* The C kernels (``robotplan/base/kernels.c``) are compiled here, once, with fixed flags
  (x86-64 with AVX2 and FMA), so the arithmetic is the same on every machine; nothing is
  chosen from the build machine's CPU. The build is optional: without a compiler the
  package installs and every caller uses its PyTorch path.
* A regular (non-editable) install copies the data folders ``robots/``, ``skeletons/``,
  ``learned/`` and ``tasks/`` into the package as ``robotplan/_data/`` (see
  ``robotplan/base/resources.py``); an editable install reads them from the checkout.
"""

import platform
import shutil
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_py import build_py

DATA_FOLDERS = ("robots", "skeletons", "learned", "tasks")
KERNEL_FLAGS = ["-O3", "-std=gnu11", "-fno-math-errno", "-mavx2", "-mfma"]


class BuildPyWithData(build_py):
    """build_py that also copies the data folders into the package (not when editable)."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        target = Path(self.build_lib) / "robotplan" / "_data"
        for name in DATA_FOLDERS:
            shutil.copytree(name, target / name, dirs_exist_ok=True,
                            ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))


kernels = Extension("robotplan.base._kernels", ["robotplan/base/kernels.c"],
                    extra_compile_args=KERNEL_FLAGS, libraries=["m"], optional=True)
x86 = platform.machine().lower() in ("x86_64", "amd64")
setup(cmdclass={"build_py": BuildPyWithData}, ext_modules=[kernels] if x86 else [])
