#!/usr/bin/env python3
"""Every relative link of README.md and docs/*.md resolves: the file exists and, for `#anchor`,
the target Markdown page has a heading with that GitHub-style anchor.

    check_doc_links.py SOURCE_ROOT [--pending PAGE...]   # exit 0 when every link resolves, else 1

--pending names pages (relative to SOURCE_ROOT) that other branches add: a link to one of them is
accepted while it is missing, and checked like any other once it exists.
    check_doc_links.py --slug 'HEADING'     # print GitHub's anchor of a heading (for writing links)
"""
import pathlib
import re
import sys
import urllib.parse

FENCE = re.compile(r"^\s*(```|~~~)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
# [text](target) and ![alt](target); the target ends at the first space or ')'.
LINK = re.compile(r"!?\[(?:[^\]\\]|\\.)*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
CODE_SPAN = re.compile(r"(`+)(?:(?!\1).)+?\1")


def prose_lines(text, blank_code=True):
    """(line number, line) outside fenced code blocks, with inline code spans blanked."""
    in_fence = False
    for number, line in enumerate(text.split("\n"), 1):
        if FENCE.match(line):
            in_fence = not in_fence
            continue
        if not in_fence:
            yield number, CODE_SPAN.sub(lambda m: " " * len(m.group(0)), line) if blank_code else line


def slug(heading):
    """GitHub's anchor of a heading: the rendered text, lower case, punctuation dropped, spaces
    to hyphens (each space, so "a — b" gives "a--b")."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # links: their text
    text = re.sub(r"<[^>]+>", "", text)  # inline HTML tags
    text = text.replace("`", "").lower()
    text = "".join(c for c in text if c.isalnum() or c in " -_")
    return text.replace(" ", "-")


def anchors(path):
    """Every anchor GitHub generates for a page's headings (repeats get -1, -2, ...)."""
    seen = {}
    result = set()
    for _, line in prose_lines(path.read_text(encoding="utf-8"), blank_code=False):
        match = HEADING.match(line)
        if not match:
            continue
        base = slug(match.group(2))
        count = seen.get(base, 0)
        seen[base] = count + 1
        result.add(base if count == 0 else f"{base}-{count}")
    return result


def page_links(path):
    raw_lines = path.read_text(encoding="utf-8").split("\n")
    for number, line in prose_lines(path.read_text(encoding="utf-8")):
        for match in LINK.finditer(line):
            yield number, raw_lines[number - 1][match.start(1):match.end(1)]


def check(root, pending=()):
    pages = [root / "README.md"] + sorted((root / "docs").glob("*.md"))
    problems = []
    cache = {}
    for page in pages:
        for number, target in page_links(page):
            if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):  # http:, https:, mailto:
                continue
            file_part, _, anchor = target.partition("#")
            resolved = (page.parent / urllib.parse.unquote(file_part)).resolve() if file_part else page
            where = f"{page.relative_to(root)}:{number}: {target}"
            if not resolved.exists():
                if resolved in {(root / p).resolve() for p in pending}:
                    continue
                problems.append(f"{where}: no such file {resolved}")
                continue
            if not anchor:
                continue
            if resolved.suffix != ".md" or resolved.is_dir():
                problems.append(f"{where}: an anchor into a file that is not a Markdown page")
                continue
            if resolved not in cache:
                cache[resolved] = anchors(resolved)
            if urllib.parse.unquote(anchor).lower() not in cache[resolved]:
                problems.append(f"{where}: no heading with anchor #{anchor} in {resolved.name}")
    return pages, problems


def main(argv):
    if len(argv) == 3 and argv[1] == "--slug":
        print(slug(argv[2]))
        return 0
    if len(argv) < 2 or (len(argv) > 2 and argv[2] != "--pending"):
        print(__doc__, file=sys.stderr)
        return 2
    root = pathlib.Path(argv[1]).resolve()
    pages, problems = check(root, argv[3:])
    for problem in problems:
        print(problem)
    links = sum(1 for page in pages for _ in page_links(page))
    print(f"{len(pages)} pages, {links} links, {len(problems)} broken")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
