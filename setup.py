"""The qm3d wheel: python/qm3d/*.py, the compiled module qm3d._qm3d built by the project's CMake
(target qm3d_python), and the LAB2000HL tables with their licence when the build finds them.

    pip install . --no-build-isolation      (metadata: pyproject.toml)

Debian 12 has no scikit-build, so this is setuptools with a CMake step: build_ext configures
the whole project (Release, tests and benchmarks off) in BUILD_BASE/temp.*/cmake, builds
qm3d_python with all cores and copies the module and the tables into the wheel. Nothing is
downloaded.

The interpreter running pip (sys.executable, e.g. a virtualenv's python) is the one CMake
builds for (PYTHON_EXECUTABLE, which pybind11 reads): its headers and extension suffix.

Environment:
    QM3D_DATA_DIR               tables to build in (else ../shared/data/lab2000hl beside the
                                checkout, else ~/.local/share/qm3d/lab2000hl, as
                                scripts/setup.sh looks; none found: the wheel has no tables)
    QM3D_CMAKE_ARGS             more CMake arguments (shell words), e.g.
                                -DQM3D_DEFAULT_DATA_DIR=/opt/tables
    CMAKE_BUILD_PARALLEL_LEVEL  build jobs (default: os.cpu_count())
    CMAKE_CXX_COMPILER_LAUNCHER as CMake reads it; when unset, ccache is used if installed
"""

import os
import re
import shlex
import shutil
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT / "python" / "build_support"))


def bdist_wheel_command():
    """setuptools' own bdist_wheel (>= 70.1) or the `wheel` package's when either is there;
    else qm3d's (python/build_support/bdist_wheel_fallback.py): no `wheel` package needed."""
    try:
        from setuptools.command.bdist_wheel import bdist_wheel  # setuptools >= 70.1
        return None
    except ImportError:
        pass
    try:
        import wheel.bdist_wheel  # noqa: F401  (registers itself as a setuptools command)
        return None
    except ImportError:
        from bdist_wheel_fallback import bdist_wheel
        return bdist_wheel
# The five tables the colour conversion reads (common/src/color.cpp) and the licence that must
# travel with them (MPL-2.0: MEPP-team/PCQM resources/).
TABLE_FILES = ("L_data.txt", "RegularGrid_0_0_1.txt", "RegularGrid_0_0_2.txt",
               "RegularGridInit_0_0_1.txt", "RegularGridInit_0_0_2.txt")
TABLE_LICENCE = "LICENSE-MPL2.txt"
# setuptools' default build/ is the CMake build directory of DEVELOPERS.md: keep out of it.
BUILD_BASE = "build-wheel"


def project_version():
    text = (ROOT / "CMakeLists.txt").read_text(encoding="utf-8")
    match = re.search(r"project\(\s*qm3d\s+VERSION\s+([0-9][0-9.]*)", text)
    if not match:
        raise RuntimeError(f"{ROOT / 'CMakeLists.txt'}: no project(qm3d VERSION ...) line")
    return match.group(1)


def has_tables(directory):
    return all((directory / name).is_file() for name in TABLE_FILES)


def find_tables():
    """The tables' directory, looked for as scripts/setup.sh does; None when absent."""
    candidates = []
    if os.environ.get("QM3D_DATA_DIR"):
        candidates.append(Path(os.environ["QM3D_DATA_DIR"]))
    candidates.append(ROOT.parent / "shared" / "data" / "lab2000hl")
    data_home = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    candidates.append(Path(data_home) / "qm3d" / "lab2000hl")
    return next((c.resolve() for c in candidates if has_tables(c)), None)


def cmake_cache_value(build_dir, name):
    for line in (build_dir / "CMakeCache.txt").read_text(encoding="utf-8").splitlines():
        if line.startswith(name + ":"):
            return line.split("=", 1)[1]
    return ""


class CMakeExtension(Extension):
    """qm3d._qm3d, made by CMake (no sources for setuptools to compile); its presence makes the
    wheel platform-specific (cpXY-cpXY-linux_ARCH)."""

    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = Path(self.build_temp).resolve() / "cmake"
        self.configure(build_dir)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
        self.spawn(["cmake", "--build", str(build_dir), "--target", "qm3d_python", "-j", jobs])
        target = Path(self.get_ext_fullpath(ext.name))
        built = build_dir / "python" / "qm3d" / target.name
        if not built.is_file():
            raise RuntimeError(f"{built}: not built (CMake's Python extension suffix differs "
                               f"from {sys.executable}'s?)")
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built, target)
        if not self.inplace:  # an editable install reads the configured directory instead
            self.bundle_tables(Path(cmake_cache_value(build_dir, "QM3D_DEFAULT_DATA_DIR")),
                               target.parent / "lab2000hl")

    def configure(self, build_dir):
        user_args = shlex.split(os.environ.get("QM3D_CMAKE_ARGS", ""))
        args = ["cmake", "-S", str(ROOT), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                f"-DPYTHON_EXECUTABLE={sys.executable}", "-DQM3D_BUILD_PYTHON=ON",
                "-DQM3D_BUILD_TESTS=OFF", "-DQM3D_BUILD_BENCH=OFF"]
        if "CMAKE_CXX_COMPILER_LAUNCHER" not in os.environ and shutil.which("ccache"):
            args += ["-DCMAKE_CXX_COMPILER_LAUNCHER=ccache", "-DCMAKE_C_COMPILER_LAUNCHER=ccache"]
        tables = find_tables()
        if tables and not any(a.startswith("-DQM3D_DEFAULT_DATA_DIR") for a in user_args):
            args.append(f"-DQM3D_DEFAULT_DATA_DIR={tables}")
        # pybind11 caches what it found for the first interpreter (headers, suffix): another
        # one (a new venv, another python) starts from an empty cache; objects are reused.
        cache = build_dir / "CMakeCache.txt"
        if cache.is_file() and cmake_cache_value(build_dir, "PYTHON_EXECUTABLE") != sys.executable:
            cache.unlink()
        self.spawn(args + user_args)

    def bundle_tables(self, source, destination):
        """Copies the tables CMake was configured with into the package (qm3d/lab2000hl, which
        qm3d/__init__.py looks for); without them or their licence, the wheel has none and
        finds tables as a build tree does ($QM3D_DATA_DIR, else the configured directory)."""
        shutil.rmtree(destination, ignore_errors=True)  # none left from an earlier build
        if not has_tables(source) or not (source / TABLE_LICENCE).is_file():
            self.warn(f"LAB2000HL tables (with {TABLE_LICENCE}) not found in '{source}': the "
                      "wheel has no tables; set QM3D_DATA_DIR when building or using it")
            return
        destination.mkdir(parents=True, exist_ok=True)
        for name in TABLE_FILES + (TABLE_LICENCE,):
            shutil.copy2(source / name, destination / name)
        if has_tables(source / "icid"):  # iCID's full-precision tables (render/icid.h)
            (destination / "icid").mkdir()
            for name in TABLE_FILES + ("README.md",):
                if (source / "icid" / name).is_file():
                    shutil.copy2(source / "icid" / name, destination / "icid" / name)


(ROOT / BUILD_BASE).mkdir(exist_ok=True)  # egg_info wants its folder to exist
BDIST_WHEEL = bdist_wheel_command()
# package_dir/packages here rather than in pyproject.toml's [tool.setuptools], which Debian 12's
# setuptools 66 calls beta (a warning on every build). The tables are not package data of the
# source tree: build_ext adds them from where CMake found them.
setup(version=project_version(),
      package_dir={"": "python"},
      packages=["qm3d"],
      include_package_data=False,
      ext_modules=[CMakeExtension("qm3d._qm3d")],
      cmdclass={"build_ext": CMakeBuild,
                **({"bdist_wheel": BDIST_WHEEL} if BDIST_WHEEL else {})},
      options={"build": {"build_base": BUILD_BASE}, "egg_info": {"egg_base": BUILD_BASE}},
      zip_safe=False)
