"""A bdist_wheel command for setuptools without one (setup.py uses it when needed).

setuptools >= 70.1 has bdist_wheel built in; older ones (Debian 12's 66.1, the 65.5 that
CPython 3.11's ensurepip installs into pyenv interpreters and venvs) take it from the separate
`wheel` package. Where neither is there, `pip wheel . --no-build-isolation` stopped with
"invalid command 'bdist_wheel'"; this command builds the same kind of wheel with setuptools
alone: `build` (the CMake extension, the package), the build directory's files, a dist-info
made from egg_info's metadata, the WHEEL file and RECORD (PEP 427, PEP 376 hashes).

The wheel is platform-specific: cpXY-cpXY-PLATFORM (the running interpreter's tags), as the
`wheel` package names a wheel with a compiled extension.
"""

import base64
import hashlib
import os
import shutil
import sys
import sysconfig
import zipfile
from email.parser import Parser
from pathlib import Path

from setuptools import Command

WHEEL_VERSION = "1.0"


def interpreter_tag():
    return "cp%d%d" % sys.version_info[:2]


def abi_tag():
    soabi = sysconfig.get_config_var("SOABI") or ""  # e.g. cpython-311-x86_64-linux-gnu
    parts = soabi.split("-")
    return "cp" + parts[1] if len(parts) > 1 and parts[0] == "cpython" else interpreter_tag()


def platform_tag():
    return sysconfig.get_platform().replace("-", "_").replace(".", "_")


def safe_name(name):
    return "".join(c if c.isalnum() or c == "." else "_" for c in name)


def requirements_as_metadata(requires_txt):
    """Requires-Dist / Provides-Extra lines from egg_info's requires.txt ([extra] sections)."""
    lines, extra = [], None
    for raw in requires_txt.splitlines():
        line = raw.strip()
        if not line:
            continue
        if line.startswith("[") and line.endswith("]"):
            extra = line[1:-1].split(":")[0]
            if extra:
                lines.append(f"Provides-Extra: {extra}")
            continue
        lines.append(f"Requires-Dist: {line}" + (f' ; extra == "{extra}"' if extra else ""))
    return lines


def metadata_from_egg_info(egg_info):
    """PKG-INFO as METADATA, with the requirements of requires.txt when it lacks them."""
    egg_info = Path(egg_info)
    text = (egg_info / "PKG-INFO").read_text(encoding="utf-8")
    headers = Parser().parsestr(text, headersonly=True)
    requires = egg_info / "requires.txt"
    if headers.get_all("Requires-Dist") is not None or not requires.is_file():
        return text
    head, sep, body = text.partition("\n\n")
    lines = head.rstrip("\n").split("\n")
    for line in requirements_as_metadata(requires.read_text(encoding="utf-8")):
        if line not in lines:
            lines.append(line)
    return "\n".join(lines) + "\n" + ("\n" + body if sep else "")


def record_line(path, arcname):
    data = Path(path).read_bytes()
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{arcname},sha256={digest},{len(data)}"


class bdist_wheel(Command):
    description = "create a wheel (setuptools alone: no `wheel` package needed)"
    user_options = [("dist-dir=", "d", "directory to put the wheel in (default: dist)")]

    def initialize_options(self):
        self.dist_dir = None

    def finalize_options(self):
        self.dist_dir = self.dist_dir or "dist"

    def egg2dist(self, egg_info, dist_info):
        """What setuptools' dist_info command asks of bdist_wheel: the dist-info of egg_info."""
        dist_info = Path(dist_info)
        shutil.rmtree(dist_info, ignore_errors=True)
        dist_info.mkdir(parents=True)
        (dist_info / "METADATA").write_text(metadata_from_egg_info(egg_info), encoding="utf-8")
        for name in ("entry_points.txt", "top_level.txt"):
            if (Path(egg_info) / name).is_file():
                shutil.copy2(Path(egg_info) / name, dist_info / name)

    def run(self):
        self.run_command("build")
        build_lib = Path(self.get_finalized_command("build").build_lib)
        egg_info = self.get_finalized_command("egg_info")
        self.run_command("egg_info")
        name = safe_name(self.distribution.get_name())
        version = safe_name(self.distribution.get_version())
        tag = f"{interpreter_tag()}-{abi_tag()}-{platform_tag()}"
        dist_info_name = f"{name}-{version}.dist-info"
        staging = Path(self.get_finalized_command("build").build_base) / "wheel-staging"
        shutil.rmtree(staging, ignore_errors=True)
        shutil.copytree(build_lib, staging)
        self.egg2dist(egg_info.egg_info, staging / dist_info_name)
        (staging / dist_info_name / "WHEEL").write_text(
            f"Wheel-Version: {WHEEL_VERSION}\nGenerator: qm3d setup.py\n"
            f"Root-Is-Purelib: false\nTag: {tag}\n", encoding="utf-8")
        os.makedirs(self.dist_dir, exist_ok=True)
        wheel_path = Path(self.dist_dir) / f"{name}-{version}-{tag}.whl"
        self.write_wheel(staging, wheel_path, dist_info_name)
        shutil.rmtree(staging, ignore_errors=True)
        self.announce(f"created {wheel_path}", level=2)

    @staticmethod
    def write_wheel(staging, wheel_path, dist_info_name):
        files = sorted(p for p in staging.rglob("*") if p.is_file() and "__pycache__" not in p.parts)
        record_name = f"{dist_info_name}/RECORD"
        records = []
        with zipfile.ZipFile(wheel_path, "w", compression=zipfile.ZIP_DEFLATED) as z:
            for path in files:
                arcname = path.relative_to(staging).as_posix()
                z.write(path, arcname)
                records.append(record_line(path, arcname))
            records.append(f"{record_name},,")
            z.writestr(record_name, "\n".join(records) + "\n")
