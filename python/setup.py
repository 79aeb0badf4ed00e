# SPDX-License-Identifier: GPL-3.0-or-later
"""Builds the compiled core with CMake (the repository's CMakeLists.txt, POINTSURF_BUILD_PYTHON=ON,
for the interpreter running this) and puts it into the package. The build folder:

- POINTSURF_BUILD_DIR when set (configured for this interpreter if it is not configured yet);
- else the repository's build/, when it is configured with the module for this interpreter (what
  ./pointsurf.sh demo and test configure, for /usr/bin/python3; a venv made from it counts): only
  the _pointsurf target is built there, on the library already compiled (the library is always
  -fPIC, so none of it is compiled again);
- else <repo>/build-python, configured here (the whole library is compiled once; ccache is used
  when present).
"""
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def log(message):
    print(f"pointsurf setup.py: {message}", file=sys.stderr, flush=True)


def cache_entries(build_dir):
    """NAME -> VALUE of build_dir's CMakeCache.txt ({} when it is not configured)."""
    cache = Path(build_dir) / "CMakeCache.txt"
    if not cache.is_file():
        return {}
    entries = {}
    for line in cache.read_text(errors="replace").splitlines():
        if line and not line.startswith(("#", "//")) and ":" in line and "=" in line:
            name_type, _, value = line.partition("=")
            entries[name_type.split(":", 1)[0]] = value
    return entries


def same_interpreter(executable):
    """True when `executable` is the interpreter running this (a venv's python is its base one)."""
    mine = {os.path.realpath(sys.executable), os.path.realpath(getattr(sys, "_base_executable", sys.executable))}
    return bool(executable) and os.path.realpath(executable) in mine


def why_not_reusable(entries):
    """None when a configured build folder builds the module for this interpreter, else why not."""
    if entries.get("POINTSURF_BUILD_PYTHON", "").upper() not in ("ON", "1", "TRUE", "YES"):
        return "it is configured without POINTSURF_BUILD_PYTHON=ON"
    exe = entries.get("Python3_EXECUTABLE") or entries.get("_Python3_EXECUTABLE")
    if not same_interpreter(exe):
        return f"it is configured for {exe}, not {sys.executable}"
    return None


def choose_build_dir():
    """(build folder, whether it must be configured here)."""
    if os.environ.get("POINTSURF_BUILD_DIR"):
        build_dir = Path(os.environ["POINTSURF_BUILD_DIR"]).resolve()
        entries = cache_entries(build_dir)
        if not entries:
            return build_dir, True
        why = why_not_reusable(entries)
        if why:
            sys.exit(f"pointsurf setup.py: POINTSURF_BUILD_DIR={build_dir} cannot build the module: {why}")
        return build_dir, False
    build_dir = ROOT / "build"
    entries = cache_entries(build_dir)
    if entries:
        why = why_not_reusable(entries)
        if why is None:
            return build_dir, False
        log(f"not reusing {build_dir}: {why}")
    build_dir = ROOT / "build-python"
    return build_dir, not cache_entries(build_dir)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir, configure = choose_build_dir()
        if configure:
            log(f"configuring {build_dir} (the library is compiled in it)")
            args = ["-DCMAKE_BUILD_TYPE=Release", "-DPOINTSURF_BUILD_PYTHON=ON", "-DPOINTSURF_BUILD_TESTS=OFF",
                    "-DPOINTSURF_BUILD_APPS=OFF", f"-DPython3_EXECUTABLE={sys.executable}"]
            if shutil.which("ninja"):
                args.append("-GNinja")
            if shutil.which("ccache"):
                args.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
            subprocess.check_call(["cmake", "-S", str(ROOT), "-B", str(build_dir), *args])
        else:
            log(f"building the module in {build_dir} (configured already; only what is missing is compiled)")
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 2))
        subprocess.check_call(["cmake", "--build", str(build_dir), "--target", "_pointsurf", "--parallel", jobs])
        built = build_dir / "python" / "pointsurf" / ("_pointsurf" + sysconfig.get_config_var("EXT_SUFFIX"))
        if not built.is_file():
            sys.exit(f"pointsurf setup.py: {built} is missing after the build (another interpreter's module?)")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built, target)


setup(ext_modules=[Extension("pointsurf._pointsurf", sources=[])], cmdclass={"build_ext": CMakeBuild})
