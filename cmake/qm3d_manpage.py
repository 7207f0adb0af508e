#!/usr/bin/env python3
"""Writes the qm3d(1) manual page from the built tool itself, so it lists exactly what the tool
has: every command with its summary and options (`qm3d --help`, `qm3d COMMAND --help`) and every
metric of the registry with the reference implementation it reproduces (`qm3d --version`).

    qm3d_manpage.py QM3D_BINARY OUT.1 [OUT.1.gz]

OUT.1.gz is the page compressed as Debian policy wants it (gzip -9n: no name, no time stamp).
"""
import gzip
import os
import re
import subprocess
import sys

SECTION = re.compile(r"^(\w[\w ]*):$")
NAME_COLUMN = 30  # CLI11's default column of option descriptions
ENTRY = re.compile(r"^  (\S.*?)(?:\s{2,}(\S.*))?$")


def tool_output(binary, *args):
    result = subprocess.run([binary, *args], capture_output=True, text=True, check=True,
                            env=dict(os.environ, COLUMNS="100000", LC_ALL="C.UTF-8"))
    return result.stdout.replace(binary, "qm3d")


def parse_help(text):
    """(description lines, usage, {section: [(spec, description)]}) of CLI11's --help."""
    description, usage, sections, current = [], "", {}, None
    for line in text.split("\n"):
        if line.startswith("Usage: "):
            usage = line[len("Usage: "):]
        elif SECTION.match(line):
            current = sections.setdefault(SECTION.match(line).group(1), [])
        elif current is None:
            if line.strip():
                description.append(line.strip())
        elif line.startswith("   ") and current:  # a description on its own line, or continued
            spec, text_so_far = current[-1]
            current[-1] = (spec, (text_so_far + " " + line.strip()).strip())
        elif ENTRY.match(line):
            match = ENTRY.match(line)
            spec, text_of_entry = match.group(1).strip(), (match.group(2) or "").strip()
            if not text_of_entry and re.match(r"^\S [A-Z]", line[NAME_COLUMN - 2:NAME_COLUMN + 1]):
                # CLI11 pads names to NAME_COLUMN: a name of 28 characters leaves one space.
                spec, text_of_entry = line[:NAME_COLUMN].strip(), line[NAME_COLUMN:].strip()
            current.append((spec, text_of_entry))
    return description, usage, sections


def parse_version(text):
    """(version line, [(metric, what it reproduces)]) of `qm3d --version`."""
    lines = [line for line in text.split("\n") if line.strip()]
    metrics = []
    for line in lines[1:]:
        name, _, reference = line.strip().partition(": ")
        metrics.append((name, reference))
    return lines[0], metrics


def roff(text):
    """Text escaped for roff: backslashes, and a leading dot or quote that would start a request."""
    text = text.replace("\\", "\\e")
    text = re.sub(r"(?<![\w])-", r"\\-", text)  # option dashes, not hyphenated words
    return "\\&" + text if text[:1] in (".", "'") else text


def entries(items):
    out = []
    for spec, description in items:
        out += [".TP", f"\\fB{roff(spec)}\\fR", roff(description) if description else ""]
    return out


def page(binary):
    version_line, metrics = parse_version(tool_output(binary, "--version"))
    description, usage, sections = parse_help(tool_output(binary, "--help"))
    commands = sections.get("Subcommands", [])
    summaries = dict(commands)
    version = version_line.split()[1] if len(version_line.split()) > 1 else ""
    out = [f'.TH QM3D 1 "" "qm3d {version}" "User Commands"',
           ".SH NAME", "qm3d \\- visual quality metrics for coloured 3D content",
           ".SH SYNOPSIS", f"\\fBqm3d\\fR [\\fIOPTIONS\\fR] \\fICOMMAND\\fR [\\fIARGS\\fR]",
           ".SH DESCRIPTION"]
    for line in description:
        out += [roff(line), ".PP"]
    out += [".SH OPTIONS", *entries(sections.get("Options", [])),
            ".SH COMMANDS", *entries(commands), ".SH METRICS",
            "Each metric is a command of its own and a name for \\fBbatch\\fR lists;",
            "the reference implementation whose numbers it reproduces:"]
    out += entries((name, " — ".join(p for p in (summaries.get(name, ""), reference) if p))
                   for name, reference in metrics)
    out += [".SH COMMAND OPTIONS"]
    for name, _ in commands:
        sub_description, sub_usage, sub_sections = parse_help(tool_output(binary, name, "--help"))
        out += [f".SS {roff(name)}", f"\\fB{roff(sub_usage)}\\fR", ".PP"]
        for section in sub_sections:
            out += [f"\\fI{section}:\\fR", *entries(sub_sections[section]), ".PP"]
    out += [".SH EXIT STATUS",
            "0 ok; 1 usage error; 2 bad input (a missing, unreadable or malformed file, a metric that",
            "cannot be computed, a batch row that records an error); 3 internal error.",
            ".SH ENVIRONMENT", ".TP", "\\fBQM3D_DATA_DIR\\fR",
            "Directory of the LAB2000HL tables when \\fB\\-\\-data\\-dir\\fR is not given.",
            ".SH SEE ALSO",
            "The pages in the docs/ folder of the source (README.md links them).",
            f".PP\n{roff(version_line)}"]
    return "\n".join(out) + "\n"


def main(argv):
    if len(argv) not in (3, 4):
        print(__doc__, file=sys.stderr)
        return 2
    text = page(argv[1])
    with open(argv[2], "w", encoding="utf-8") as f:
        f.write(text)
    if len(argv) == 4:
        with open(argv[3], "wb") as raw, gzip.GzipFile(filename="", mode="wb", fileobj=raw,
                                                       compresslevel=9, mtime=0) as f:
            f.write(text.encode("utf-8"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
