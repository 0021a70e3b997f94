#!/usr/bin/python3
"""The Python package `aia` as a wheel (`pip install --no-build-isolation .`,
docs/python.md): CMake builds the module, the plugins and the CLI, and the
wheel holds them with the models and scenarios in an installed layout,

    aia/            the package (_aia, *.py, _install.py)
    aia/bin/aia     the CLI (also the `aia` command of the environment)
    aia/lib/aia/    the plugins (libtorch's, the codecs')
    aia/share/aia/  models/, scenarios/

so that the package loads only its own files (aia/_install.py).

The CMake build folder is AIA_BUILD_DIR when set (an existing build is
reused: `AIA_BUILD_DIR=build pip install --no-build-isolation .`), else
build/pip, configured on first use (the whole build: about an hour on two
cores); AIA_JOBS sets the build's parallelism.
"""
import glob
import os
import re
import shutil
import subprocess
import sys

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.dist import Distribution

HERE = os.path.dirname(os.path.abspath(__file__))


def version():
    text = open(os.path.join(HERE, "CMakeLists.txt")).read()
    return re.search(r"project\(aia VERSION ([0-9.]+)", text).group(1)


def cmake_build():
    """The CMake build folder, built for the wheel."""
    build = os.environ.get("AIA_BUILD_DIR") or os.path.join("build", "pip")
    if not os.path.isabs(build):
        build = os.path.join(HERE, build)
    if not os.path.exists(os.path.join(build, "CMakeCache.txt")):
        generator = ["-G", "Ninja"] if shutil.which("ninja") else []
        subprocess.check_call([
            "cmake", "-S", HERE, "-B", build, *generator,
            "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython_EXECUTABLE={sys.executable}",
            "-DAIA_BUILD_TESTS=OFF", "-DAIA_BUILD_BENCHMARKS=OFF",
            "-DAIA_WITH_MPI=OFF"])
    jobs = os.environ.get("AIA_JOBS")
    subprocess.check_call(["cmake", "--build", build, "--target", "aia_python",
                           "aia", *(["-j", jobs] if jobs else [])])
    return build


class BuildWithCMake(build_py):
    """build_py, then the CMake products and data beside the .py files."""

    def run(self):
        super().run()
        build = cmake_build()
        pkg = os.path.join(self.build_lib, "aia")
        for f in glob.glob(os.path.join(build, "python", "aia", "_aia*.so")):
            shutil.copy2(f, pkg)
        os.makedirs(os.path.join(pkg, "bin"), exist_ok=True)
        shutil.copy2(os.path.join(build, "aia"), os.path.join(pkg, "bin"))
        lib = os.path.join(pkg, "lib", "aia")
        os.makedirs(lib, exist_ok=True)
        for name in ("libaia_torch.so", "libaia_media.so"):
            shutil.copy2(os.path.join(build, name), lib)
        share = os.path.join(pkg, "share", "aia")
        os.makedirs(os.path.join(share, "models"), exist_ok=True)
        for name in ("igbnet.pt", "igbnet_10x10.pt", "igbnet_learned.pt"):
            shutil.copy2(os.path.join(HERE, "models", name),
                         os.path.join(share, "models"))
        shutil.copytree(os.path.join(HERE, "scenarios"),
                        os.path.join(share, "scenarios"), dirs_exist_ok=True)
        with open(os.path.join(pkg, "_install.py"), "w") as f:
            f.write('"""Written by setup.py: where this wheel\'s plugins and '
                    'data are, relative to the package."""\n'
                    'PLUGIN_DIR = "lib/aia"\nDATA_DIR = "share/aia"\n')


class BinaryDistribution(Distribution):
    """A wheel for this platform and Python (it holds compiled code)."""

    def has_ext_modules(self):
        return True


os.makedirs(os.path.join(HERE, "build", "setuptools"), exist_ok=True)
setup(
    name="aia",
    version=version(),
    description="Multi-robot Active Information Acquisition testbed "
                "(MuJoCo, DKF, I-GBNet) from Python",
    python_requires=">=3.9",
    install_requires=["numpy"],
    packages=["aia"],
    package_dir={"aia": "python/aia"},
    cmdclass={"build_py": BuildWithCMake},
    distclass=BinaryDistribution,
    entry_points={"console_scripts": ["aia = aia._cli:main"]},
    options={"build": {"build_base": "build/setuptools"},
             "egg_info": {"egg_base": "build/setuptools"}},
    zip_safe=False,
)
