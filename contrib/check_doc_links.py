#!/usr/bin/env python3
"""Check that every relative link in README.md and doc/**/*.md resolves.

Markdown links [text](target) and images ![alt](target) whose target is not a
URL (http:, https:, mailto:) or a pure anchor must name an existing file or
directory, relative to the page that holds the link. An anchor after the file
(page.md#section) must match a heading of that page, as GitHub makes anchors.
Plain mentions of a page by its path from the repository root (doc/name.md)
must name an existing file too. Prints each broken link as FILE:LINE: target (why) and exits 1 if any.

Usage: python3 contrib/check_doc_links.py [REPOSITORY_ROOT]
"""
import os
import re
import sys

LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
MENTION = re.compile(r"(?<![\w/.])(doc/[\w./-]*\w\.md)")
FENCE = re.compile(r"^\s*(```|~~~)")


def anchor(title):
    """GitHub's anchor for a heading: lower case, punctuation dropped,
    spaces to hyphens."""
    title = re.sub(r"`|\*|_(?=\W)|(?<=\W)_", "", title.strip()).lower()
    title = re.sub(r"[^\w\- ]", "", title, flags=re.UNICODE)
    return title.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        found, seen, fenced = set(), {}, False
        with open(path, encoding="utf-8") as f:
            for line in f:
                if FENCE.match(line):
                    fenced = not fenced
                    continue
                m = None if fenced else HEADING.match(line)
                if m:
                    a = anchor(m.group(2))
                    n = seen.get(a, 0)
                    seen[a] = n + 1
                    found.add(a if n == 0 else "%s-%d" % (a, n))
        cache[path] = found
    return cache[path]


def pages(root):
    yield os.path.join(root, "README.md")
    for d, _, files in os.walk(os.path.join(root, "doc")):
        for name in sorted(files):
            if name.endswith(".md"):
                yield os.path.join(d, name)


def check(root):
    broken = 0
    for page in pages(root):
        fenced = False
        with open(page, encoding="utf-8") as f:
            lines = f.readlines()
        for number, line in enumerate(lines, 1):
            if FENCE.match(line):
                fenced = not fenced
                continue
            if fenced:
                continue
            for m in LINK.finditer(re.sub(r"`[^`]*`", "", line)):
                target = m.group(1)
                if re.match(r"^[a-z]+:", target):
                    continue
                file, _, frag = target.partition("#")
                path = os.path.normpath(os.path.join(os.path.dirname(page), file)) if file else page
                why = None
                if not os.path.exists(path):
                    why = "no such file"
                elif frag and path.endswith(".md") and frag not in anchors(path):
                    why = "no heading with this anchor"
                if why:
                    broken += 1
                    print("%s:%d: %s (%s)" % (os.path.relpath(page, root), number, target, why))
            for m in MENTION.finditer(line):
                if not os.path.exists(os.path.join(root, m.group(1))):
                    broken += 1
                    print("%s:%d: %s (no such page)" % (os.path.relpath(page, root), number, m.group(1)))
    return broken


if __name__ == "__main__":
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    n = check(os.path.abspath(root))
    print("%d broken link%s" % (n, "" if n == 1 else "s"))
    sys.exit(1 if n else 0)
