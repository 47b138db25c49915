"""Builds the Python package vpm for pip (`pip install --no-build-isolation .`) with the project's
own CMake build: the library and the pybind11 module vpm._vpm are built in build-pip/ (beside
build/, so ccache reuses what a normal build compiled), and the wheel holds python/vpm/*, the
module and libvpm.so, the module finding the library beside itself (its RPATH: $ORIGIN). Needs Debian's build
tools and libraries (scripts/setup.sh); nothing is downloaded."""
import glob
import os
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE = os.path.dirname(os.path.abspath(__file__))


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        # VPM_PIP_BUILD_DIR: an existing build folder to take the module from (tests); it is
        # configured only when new, so its own settings stay
        build = os.environ.get("VPM_PIP_BUILD_DIR", os.path.join(SOURCE, "build-pip"))
        configure = ["cmake", "-S", SOURCE, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DVPM_BUILD_TESTS=OFF",
                     "-DVPM_BUILD_BENCH=OFF", "-DVPM_BUILD_PYTHON=ON",
                     f"-DPython3_EXECUTABLE={sys.executable}"]
        if shutil.which("ccache"):
            configure.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
        if not os.path.exists(os.path.join(build, "CMakeCache.txt")):
            subprocess.run(configure, check=True)
        subprocess.run(["cmake", "--build", build, "--target", "_vpm", "-j", os.environ.get("JOBS", "2")], check=True)
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        module = glob.glob(os.path.join(build, "python", "vpm", "_vpm*.so"))
        if len(module) != 1:
            raise RuntimeError(f"{build}/python/vpm: expected one _vpm module, found {module}")
        shutil.copy2(module[0], target)
        for lib in glob.glob(os.path.join(build, "libvpm.so*")):
            shutil.copy2(lib, os.path.dirname(target), follow_symlinks=True)


setup(packages=["vpm"], package_dir={"vpm": "python/vpm"}, package_data={"vpm": ["*.pyi", "py.typed"]},
      ext_modules=[Extension("vpm._vpm", sources=[])], cmdclass={"build_ext": CMakeBuild}, zip_safe=False)
