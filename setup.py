"""Builds the pcl_dacpo extension module with the project's CMake (target _core:
the C core, the support library and the pybind11 wrapper; PCL, tools and tests
off) for the interpreter that runs pip. Metadata lives in pyproject.toml."""
import os
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = os.path.dirname(os.path.abspath(__file__))


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = os.path.abspath(os.path.join(self.build_temp, "cmake"))
        cfg = ["cmake", "-S", ROOT, "-B", build, "-DCMAKE_BUILD_TYPE=Release",
               "-DDACPO_BUILD_PCL=OFF", "-DDACPO_BUILD_TOOLS=OFF",
               "-DDACPO_BUILD_TESTS=OFF", "-DDACPO_BUILD_SAMPLES=OFF",
               "-DDACPO_BUILD_PYTHON=ON", "-DPython3_EXECUTABLE=" + sys.executable]
        subprocess.check_call(cfg)
        subprocess.check_call(["cmake", "--build", build, "--target", "_core",
                               "-j", str(os.cpu_count() or 2)])
        built = os.path.join(build, "wrappers", "python", "pcl_dacpo")
        module = [f for f in os.listdir(built) if f.startswith("_core") and f.endswith(".so")]
        if not module:
            raise RuntimeError("CMake built no _core module in " + built)
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copy2(os.path.join(built, module[0]), target)


setup(ext_modules=[Extension("pcl_dacpo._core", sources=[])],
      cmdclass={"build_ext": CMakeBuild})
