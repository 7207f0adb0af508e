#!/usr/bin/env python3
"""Runs every command of README.md's quick start as printed, from the source root, and compares
what it prints with the output the README shows; then every example of docs/*.md marked to run.

    run_quick_start.py SOURCE_ROOT TOOL_DIR [PYTHON_DIR]

Without PYTHON_DIR (a build without the Python package) the commands that run python are skipped.

The quick start is the fenced block after the line `<!-- quick-start -->`: a line starting with
`$ ` is a command, the lines after it (up to the next command) the stdout it shows. Each command runs
in bash from SOURCE_ROOT after the `export` lines before it (as a user's shell would keep them); after
those exports TOOL_DIR (the qm3d under test) and PYTHON_DIR (its Python package) come first on PATH /
PYTHONPATH, so the test checks this build even where the README's `build/` is another one.

An example of a docs page is a fenced block right after the line `<!-- example: runs -->`; the
blocks of one page run in turn in one scratch folder holding a link `data` to the clone's data/ (so
they can write their outputs), with the `export` and `cd` lines before each command. A marked
```python block is a script run by Debian's python3 (the interpreter the package is built for).

Shown output is compared line by line with the first lines of stdout (then of stderr, where stdout
has fewer lines: progress and summaries go there): words must be equal, a number
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
EXAMPLE_MARKER = "<!-- example: runs -->"
NUMBER = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")
TIMEOUT_S = 120


def marked_blocks(page, marker):
    """[(command, [shown output lines])] of every fenced block right after a `marker` line."""
    lines = page.read_text(encoding="utf-8").split("\n")
    steps = []
    for number, line in enumerate(lines):
        if line.strip() == marker:
            steps += block_steps(page, lines, number + 1)
    return steps


def block_steps(page, lines, start):
    if start >= len(lines) or not lines[start].startswith("```"):
        raise SystemExit(f"{page}:{start}: no fenced block right after the marker")
    steps = []
    if lines[start].strip() == "```python":  # a script: run with Debian's python3, nothing shown
        end = lines.index("```", start + 1)
        script = "\n".join(lines[start + 1:end])
        return [(f"/usr/bin/python3 - <<'PYTHON_EXAMPLE'\n{script}\nPYTHON_EXAMPLE", [])]
    for line in lines[start + 1:]:
        if line.startswith("```"):
            return steps
        if line.startswith("$ "):
            steps.append((line[2:], []))
        elif steps:
            steps[-1][1].append(line)
        elif line.strip():
            raise SystemExit(f"{page}: output before any command: {line}")
    raise SystemExit(f"{page}: a marked block is not closed")


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
    steps = marked_blocks(root / "README.md", MARKER)
    if not steps:
        raise SystemExit("README.md: the quick start has no command")
    pins = [f'export PATH="{tool_dir}:$PATH"']
    if python_dir:
        pins.append(f'export PYTHONPATH="{python_dir}${{PYTHONPATH:+:$PYTHONPATH}}"')
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as home:
        env["HOME"] = home  # a fresh user's home: no state from earlier runs
        print("README.md quick start:")
        failures = run_steps(steps, root, pins, python_dir, env)
        count = len(steps)
        for page in sorted((root / "docs").glob("*.md")):
            steps = marked_blocks(page, EXAMPLE_MARKER)
            if not steps:
                continue
            print(f"{page.relative_to(root)}:")
            with tempfile.TemporaryDirectory() as work:
                os.symlink(root / "data", pathlib.Path(work) / "data")
                failures += run_steps(steps, pathlib.Path(work), pins, python_dir, env)
            count += len(steps)
    print(f"{count} commands, {failures} failed")
    return 1 if failures else 0


def run_steps(steps, cwd, pins, python_dir, env):
    """Runs each command after the `export`/`cd` lines before it; the number that failed."""
    exports, failures = [], 0
    for command, shown in steps:
        if not python_dir and re.search(r"\bpython3?\b", command):
            print(f"skip  $ {command.splitlines()[0]}  (no Python package in this build)")
            continue
        script = "\n".join(["set -e", *exports, *pins, command])
        try:
            result = subprocess.run(["bash", "-c", script], cwd=cwd, env=env, capture_output=True,
                                    text=True, timeout=TIMEOUT_S)
        except subprocess.TimeoutExpired:
            print(f"FAIL  $ {command.splitlines()[0]}\n      no result after {TIMEOUT_S} s")
            failures += 1
            continue
        problems = []
        if result.returncode != 0:
            problems.append(f"exit code {result.returncode}: {result.stderr.strip()[-500:]}")
        actual = result.stdout.rstrip("\n").split("\n") if result.stdout.strip() else []
        shown = [line for line in shown if line.strip()]
        if len(actual) < len(shown):  # what a terminal shows: stdout, then the messages on stderr
            actual += result.stderr.rstrip("\n").split("\n") if result.stderr.strip() else []
        if len(actual) < len(shown):
            problems.append(f"prints {len(actual)} lines, the README shows {len(shown)}")
        for number, (s, a) in enumerate(zip(shown, actual), 1):
            reason = compare_line(s, a)
            if reason:
                problems.append(f"output line {number}: {reason}\n    shown:  {s}\n    actual: {a}")
        print(("FAIL" if problems else "ok  ") + f"  $ {command.splitlines()[0]}")
        for problem in problems:
            print("      " + problem)
        failures += bool(problems)
        if re.match(r"^(export|cd) ", command):
            exports.append(command)
    return failures


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
