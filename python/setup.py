# SPDX-License-Identifier: GPL-3.0-or-later
"""Builds the compiled core with CMake (the repository's CMakeLists.txt, POINTSURF_BUILD_PYTHON=ON,
for the interpreter running this) and puts it into the package. The build folder is
<repo>/build-python (POINTSURF_BUILD_DIR overrides it); ccache is used when present."""
import os
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = Path(os.environ.get("POINTSURF_BUILD_DIR", ROOT / "build-python"))
        args = ["-DCMAKE_BUILD_TYPE=Release", "-DPOINTSURF_BUILD_PYTHON=ON", "-DPOINTSURF_BUILD_TESTS=OFF",
                "-DPOINTSURF_BUILD_APPS=OFF", f"-DPython3_EXECUTABLE={sys.executable}"]
        if shutil.which("ninja"):
            args.append("-GNinja")
        if shutil.which("ccache"):
            args.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
        if not (build_dir / "CMakeCache.txt").exists():
            subprocess.check_call(["cmake", "-S", str(ROOT), "-B", str(build_dir), *args])
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 2))
        subprocess.check_call(["cmake", "--build", str(build_dir), "--target", "_pointsurf", "--parallel", jobs])
        built = next((build_dir / "python" / "pointsurf").glob("_pointsurf*.so"))
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built, target)


setup(ext_modules=[Extension("pointsurf._pointsurf", sources=[])], cmdclass={"build_ext": CMakeBuild})
