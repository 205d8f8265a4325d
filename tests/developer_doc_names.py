#!/usr/bin/env python3
"""Every code name that the developer pages quote exists in the code.

The pages: doc/developer.md, the implementation pages beside the
reference pages (doc/solid_implementation.md, doc/track_measures.md) and
the reference pages that point to them (doc/solid.md, doc/cases.md),
and doc/flow.md.
Checks the names in backticks and the Class::member names in the fenced
diagrams: paths of the repository (source/..., include/...,
tests/..., doc/..., prm/..., contrib/...) must exist; a class name (CamelCase)
must be declared (class/struct/using/enum) in include/, source/ or tests/; in
Class::member the member must appear as a word in a file that declares the
class or in its source file; a function name written as name() must appear
as a word in include/, source/ or tests/. Prints every name it checked that
is missing and exits 1 if there is one.
Usage: developer_doc_names.py [repository root]
"""
import os
import re
import sys

root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..")
PAGES = ("developer.md", "solid_implementation.md", "track_measures.md",
         "solid.md", "cases.md", "flow.md")

code = {}
for top in ("include", "source", "tests"):
    for d, _, files in os.walk(os.path.join(root, top)):
        for f in files:
            if f.endswith((".h", ".cc")):
                p = os.path.join(d, f)
                code[p] = open(p, encoding="utf-8", errors="replace").read()


# per file: its words and the names it declares, read once
words = {p: set(re.findall(r"\w+", text)) for p, text in code.items()}
declared = {
    p: set(re.findall(r"(?=\b(?:class|struct|enum|using|namespace)\s+(\w+))", text))
    for p, text in code.items()}


def declaring_files(cls):
    found = [p for p in code if cls in declared[p]]
    # the source file beside a header holds the members' definitions
    more = []
    for p in found:
        if "/include/femp/" in p and p.endswith(".h"):
            s = p.replace("/include/femp/", "/source/")[:-2] + ".cc"
            if s in code:
                more.append(s)
    return found + more


def word_in(word, files):
    return any(word in words[p] for p in files)


ident = r"[A-Za-z_][A-Za-z_0-9]*"
# names of the libraries femp builds on, not of femp's code
EXTERNAL = {"std", "dealii", "Utilities", "Patterns", "LinearAlgebra",
            "parallel", "Particles", "DoFHandler", "ParticleHandler",
            "Triangulation", "TrilinosWrappers", "FunctionParser"}


def check_page(doc):
    """The code names of one page: (number checked, missing names)."""
    checked = 0
    missing = []
    # names in backticks, and Class::member names in the fenced diagrams
    tokens = set(re.findall(r"`([^`\n]+)`", re.sub(r"```.*?```", "", doc, flags=re.S)))
    for block in re.findall(r"```.*?```", doc, flags=re.S):
        tokens |= set(re.findall(ident + r"(?:<dim>)?(?:::" + ident + r")+", block))
    for token in sorted(tokens):
        t = token.strip()
        if re.match(r"^(source|include|tests|doc|prm|contrib)/", t) and " " not in t:
            if "<" in t or "*" in t:
                continue  # a pattern such as tests/<name>.cc
            checked += 1
            if not os.path.exists(os.path.join(root, t.rstrip("/"))):
                missing.append(t + " (no such path)")
            continue
        # Class::member::... with optional template arguments and call brackets
        name = re.sub(r"<[^<>]*>", "", t)
        name = re.sub(r"\(.*\)$", "", name)
        if re.fullmatch(ident + r"(::" + ident + r")+", name):
            parts = name.split("::")
            if parts[0] in EXTERNAL:
                continue
            checked += 1
            files = declaring_files(parts[0])
            if not files:
                missing.append(t + " (no class " + parts[0] + ")")
                continue
            for member in parts[1:]:
                if not word_in(member, files):
                    missing.append(t + " (no " + member + " in " + parts[0] + ")")
                    break
                sub = declaring_files(member)
                if sub:
                    files = files + sub
            continue
        if re.fullmatch(r"[A-Z][a-z]+([A-Z][a-z0-9]*)+", name):  # CamelCase class
            if name in EXTERNAL:
                continue
            checked += 1
            if not declaring_files(name):
                missing.append(t + " (no class)")
            continue
        if re.fullmatch(ident + r"\(\)", t):  # a function: name()
            if re.search(r"(^|_)x(_|\()", t):
                continue  # a placeholder such as setup_x()
            checked += 1
            if not word_in(t[:-2], code):
                missing.append(t + " (no such function)")
    return checked, missing


failed = False
for page in PAGES:
    doc = open(os.path.join(root, "doc", page), encoding="utf-8").read()
    checked, missing = check_page(doc)
    print("%s: %d code names checked, %d missing" % (page, checked, len(missing)))
    for m in missing:
        print("  missing: " + m)
    failed = failed or bool(missing)
sys.exit(1 if failed else 0)
