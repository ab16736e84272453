"""Builds the compiled module overtake._overtake with CMake for `pip install .`.

The module is the CMake target overtake_py. It is built in OVERTAKE_BUILD_DIR (default
build/release, the folder `make build` and `make demo` use): an existing build folder is only
brought up to date; a missing one is configured first with the demo preset's settings (no
tests or benchmarks). OVERTAKE_BUILD_JOBS sets the build's parallel jobs.
"""

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def run(self):
        for ext in self.extensions:
            self.build_cmake(ext)

    def build_cmake(self, ext):
        if shutil.which("cmake") is None:
            sys.exit("overtake: building the Python module needs cmake (scripts/install-deps.sh --demo)")
        build_dir = Path(os.environ.get("OVERTAKE_BUILD_DIR", ROOT / "build" / "release")).resolve()
        if build_dir.exists() and not build_dir.is_dir():
            sys.exit(f"overtake: OVERTAKE_BUILD_DIR={build_dir} is not a folder")
        if not (build_dir / "CMakeCache.txt").exists():
            configure = ["cmake", "-S", str(ROOT), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                         "-DOVERTAKE_BUILD_TESTS=OFF", "-DOVERTAKE_BUILD_BENCH=OFF",
                         f"-DPython3_EXECUTABLE={sys.executable}"]
            if shutil.which("ninja"):
                configure += ["-G", "Ninja"]
            subprocess.run(configure, check=True)
        build = ["cmake", "--build", str(build_dir), "--target", "overtake_py"]
        jobs = os.environ.get("OVERTAKE_BUILD_JOBS")
        if jobs:
            build += ["--parallel", jobs]
        subprocess.run(build, check=True)
        built = list((build_dir / "python" / "overtake").glob("_overtake*.so"))
        if len(built) != 1:
            sys.exit(f"overtake: expected one compiled module in {build_dir / 'python' / 'overtake'}, found {len(built)}")
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        if not built[0].name.endswith(suffix):
            sys.exit(f"overtake: {built[0]} was built for another Python than this one ({suffix}); "
                     "set OVERTAKE_BUILD_DIR to a new folder to build it for this one")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)


# setuptools' own folders under build/ (git-ignored), not beside the sources.
(ROOT / "build" / "setuptools").mkdir(parents=True, exist_ok=True)
setup(
    ext_modules=[CMakeExtension("overtake._overtake")],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": "build/setuptools"}, "egg_info": {"egg_base": "build/setuptools"}},
)
