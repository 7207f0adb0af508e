#!/usr/bin/env python3
"""No module includes a header of a module above it (docs/layout.md, "Which module may include
which"). Every `#include "qm3d/..."` of a module's sources is resolved to the module whose
folder holds that header (the deprecated forwarding headers in evaluation/compat/ belong to
evaluation, whatever their path says), and that module's level must not be higher.

    check_layering.py SOURCE_ROOT    # exit 0 when every include goes down or sideways, else 1
    check_layering.py --self-test    # the check itself fails on an upward include
"""
import pathlib
import re
import sys
import tempfile

# Folder -> level, lowest first: common <- metrics <- render / scoring <- evaluation / study /
# report <- the tool and the Python module. Within a level, a module may include another
# (render reads meshes; report draws evaluation results), never one of a higher level.
LEVELS = {
    "common": 0,
    "mesh_metric": 1,
    "pointcloud_metric": 1,
    "render": 2,
    "scoring": 2,
    "evaluation": 3,
    "study": 3,
    "report": 3,
    "apps": 4,
    "python": 4,
}
# Where a module's public headers live (relative to its folder).
HEADER_DIRS = ("include", "compat")
INCLUDE = re.compile(r'^\s*#\s*include\s+"(qm3d/[^"]+)"', re.M)
SOURCES = (".h", ".hpp", ".cpp", ".cc", ".in")


def header_owners(root):
    """{"qm3d/x/y.h": module folder} for every public header of every module."""
    owners = {}
    for module in LEVELS:
        for sub in HEADER_DIRS:
            base = root / module / sub
            if not base.is_dir():
                continue
            for path in base.rglob("*"):
                if path.is_file():
                    name = path.relative_to(base).as_posix()
                    if name.endswith(".in"):
                        name = name[:-3]  # configured headers (version.h.in)
                    owners[name] = module
    return owners


def violations(root):
    owners = header_owners(root)
    found = []
    for module, level in LEVELS.items():
        folder = root / module
        if not folder.is_dir():
            continue
        for path in sorted(folder.rglob("*")):
            if not path.is_file() or path.suffix not in SOURCES:
                continue
            text = path.read_text(encoding="utf-8", errors="replace")
            for match in INCLUDE.finditer(text):
                owner = owners.get(match.group(1))
                if owner is not None and LEVELS[owner] > level:
                    line = text.count("\n", 0, match.start()) + 1
                    found.append(f"{path.relative_to(root)}:{line}: {module} (level {level}) "
                                 f"includes {match.group(1)} of {owner} (level {LEVELS[owner]})")
    return found


def self_test():
    with tempfile.TemporaryDirectory() as tmp:
        root = pathlib.Path(tmp)
        (root / "common/include/qm3d/common").mkdir(parents=True)
        (root / "evaluation/include/qm3d/evaluation").mkdir(parents=True)
        (root / "evaluation/include/qm3d/evaluation/e.h").write_text('#include "qm3d/common/c.h"\n')
        (root / "common/include/qm3d/common/c.h").write_text("#pragma once\n")
        if violations(root):
            print("self-test: a downward include was refused")
            return 1
        (root / "common/include/qm3d/common/c.h").write_text('#include "qm3d/evaluation/e.h"\n')
        if len(violations(root)) != 1:
            print("self-test: an upward include was not found")
            return 1
    print("self-test: ok")
    return 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    if len(argv) != 2:
        print(__doc__)
        return 2
    found = violations(pathlib.Path(argv[1]))
    for v in found:
        print(v)
    if found:
        print(f"{len(found)} upward includes (docs/layout.md says which module may include which)")
        return 1
    print("layering: no module includes a header of a module above it")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
