#!/usr/bin/env python3
"""Runs every command of README.md's quick start as printed, from the source root, and compares
what it prints with the output the README shows.

    run_quick_start.py SOURCE_ROOT TOOL_DIR [PYTHON_DIR]

Without PYTHON_DIR (a build without the Python package) the commands that run python are skipped.

The quick start is the fenced block after the line `<!-- quick-start -->`: a line starting with
`$ ` is a command, the lines after it (up to the next command) the stdout it shows. Each command runs
in bash from SOURCE_ROOT after the `export` lines before it (as a user's shell would keep them); after
those exports TOOL_DIR (the qm3d under test) and PYTHON_DIR (its Python package) come first on PATH /
PYTHONPATH, so the test checks this build even where the README's `build/` is another one.

Shown output is compared line by line with the first lines of stdout: words must be equal, a number
must equal the printed one at the printed digits, and `…` ends the comparison of its line. A
command that fails, prints too few lines or another number fails the test (exit 1).
"""
import os
import pathlib
import re
import subprocess
import sys
import tempfile

MARKER = "<!-- quick-start -->"
NUMBER = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")
TIMEOUT_S = 120


def quick_start(readme):
    """[(command, [shown output lines])] of the fenced block after MARKER."""
    lines = readme.read_text(encoding="utf-8").split("\n")
    start = lines.index(MARKER) + 1
    if not lines[start].startswith("```"):
        raise SystemExit(f"{readme}: no fenced block right after {MARKER}")
    steps = []
    for line in lines[start + 1:]:
        if line.startswith("```"):
            return steps
        if line.startswith("$ "):
            steps.append((line[2:], []))
        elif steps:
            steps[-1][1].append(line)
        elif line.strip():
            raise SystemExit(f"{readme}: quick start output before any command: {line}")
    raise SystemExit(f"{readme}: the quick-start block is not closed")


def split_words(line):
    """Words with the punctuation qm3d prints around numbers split off."""
    return [w for w in re.split(r"[\s,()\[\];]+", line) if w]


def number_matches(shown, actual):
    """The actual number, rounded to the digits shown, is the shown one."""
    try:
        value = float(actual)
    except ValueError:
        return False
    mantissa = re.sub(r"[eE].*", "", shown).lstrip("+-")
    digits = len(mantissa.replace(".", "").lstrip("0")) or 1
    return float(f"{value:.{digits}g}") == float(shown)


def compare_line(shown, actual):
    """None when `actual` prints what `shown` shows, else the reason."""
    shown_words, actual_words = split_words(shown.split("…")[0]), split_words(actual)
    truncated = "…" in shown
    if len(actual_words) < len(shown_words) or (not truncated and len(actual_words) != len(shown_words)):
        return f"{len(actual_words)} words where the README shows {len(shown_words)}"
    for s, a in zip(shown_words, actual_words):
        same = number_matches(s, a) if NUMBER.match(s) else s == a
        if not same:
            return f"{a!r} where the README shows {s!r}"
    return None


def run(root, tool_dir, python_dir):
    steps = quick_start(root / "README.md")
    if not steps:
        raise SystemExit("README.md: the quick start has no command")
    exports = []
    pins = [f'export PATH="{tool_dir}:$PATH"']
    if python_dir:
        pins.append(f'export PYTHONPATH="{python_dir}${{PYTHONPATH:+:$PYTHONPATH}}"')
    failures = 0
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as home:
        env["HOME"] = home  # a fresh user's home: no state from earlier runs
        for command, shown in steps:
            if not python_dir and re.search(r"\bpython3?\b", command):
                print(f"skip  $ {command}  (no Python package in this build)")
                continue
            script = "\n".join(["set -e", *exports, *pins, command])
            result = subprocess.run(["bash", "-c", script], cwd=root, env=env, capture_output=True,
                                    text=True, timeout=TIMEOUT_S)
            problems = []
            if result.returncode != 0:
                problems.append(f"exit code {result.returncode}: {result.stderr.strip()[-500:]}")
            actual = result.stdout.rstrip("\n").split("\n") if result.stdout.strip() else []
            shown = [line for line in shown if line.strip()]
            if len(actual) < len(shown):
                problems.append(f"prints {len(actual)} lines, the README shows {len(shown)}")
            for number, (s, a) in enumerate(zip(shown, actual), 1):
                reason = compare_line(s, a)
                if reason:
                    problems.append(f"output line {number}: {reason}\n    shown:  {s}\n    actual: {a}")
            print(("FAIL" if problems else "ok  ") + f"  $ {command}")
            for problem in problems:
                print("      " + problem)
            failures += bool(problems)
            if command.startswith("export "):
                exports.append(command)
    print(f"{len(steps)} quick-start commands, {failures} failed")
    return 1 if failures else 0


def main(argv):
    if len(argv) not in (3, 4):
        print(__doc__, file=sys.stderr)
        return 2
    root = pathlib.Path(argv[1]).resolve()
    tool_dir = pathlib.Path(argv[2]).resolve()
    python_dir = pathlib.Path(argv[3]).resolve() if len(argv) == 4 and argv[3] else None
    return run(root, tool_dir, python_dir)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
