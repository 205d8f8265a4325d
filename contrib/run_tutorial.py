#!/usr/bin/env python3
"""Run the commands of a tutorial page and check its figures.

    python3 contrib/run_tutorial.py doc/tutorials/first_track.md \
        --build build --work build/tutorial/first_track [--list]

A tutorial page (doc/tutorials/*.md) marks what a test runs and checks with
HTML comments, invisible on the rendered page:

    <!-- run -->            the next ```sh block is run (blocks without it
                            are shown only: runs of hours, cluster scripts)
    <!-- check: file PATH -->
                            PATH exists and is not empty
    <!-- check: csv PATH COLUMN REDUCER VALUE TOLERANCE -->
                            REDUCER (max, min, last, maxabs) of COLUMN in
                            the CSV file PATH lies within the relative
                            TOLERANCE of VALUE; a PATH with '*' takes the
                            last match in name order
    <!-- check: same PATH_A PATH_B -->
                            the two files are equal byte for byte
    <!-- check: log REGEX -->
                            the printout of the commands run so far holds
                            a line matching REGEX (Python syntax)

Checks run in order, each after the blocks above it. The blocks run with
bash -e -o pipefail from WORK, which holds links to the repository's
prm/, contrib/ and doc/ and a link build -> BUILD, so the page's commands
read as they would from the repository root. Open MPI is allowed, through
its environment, to oversubscribe the cores and to run as root, as the
tests do; 'python3' becomes this interpreter (it needs numpy for
contrib/femp_post.py, which also reads the CSV files of the checks).
Exit status 0 when every block ran and every check passed.
"""
import argparse
import filecmp
import glob
import os
import re
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "contrib"))
import femp_post  # noqa: E402


def parse(page):
    """The page's steps in order: ('run', text) and ('check', words)."""
    steps = []
    run_next = False
    in_block = None
    for line in open(page, encoding="utf-8"):
        s = line.strip()
        if in_block is not None:
            if s.startswith("```"):
                if run_next:
                    steps.append(("run", "".join(in_block)))
                in_block = None
                run_next = False
            else:
                in_block.append(line)
            continue
        if s.startswith("```"):
            in_block = []
            continue
        m = re.fullmatch(r"<!--\s*run\s*-->", s)
        if m:
            run_next = True
            continue
        m = re.fullmatch(r"<!--\s*check:\s*(.*?)\s*-->", s)
        if m:
            steps.append(("check", m.group(1)))
    return steps


def block_env(work):
    """The environment of the blocks: Open MPI allowed to run as root and
    to put more ranks than cores (as the tests do), also for scripts that
    call mpirun themselves; 'python3' is this interpreter, also for
    scripts that call python3 themselves."""
    env = dict(os.environ)
    bin_dir = os.path.join(work, ".bin")
    if not os.path.isdir(bin_dir):
        os.makedirs(bin_dir)
        os.symlink(sys.executable, os.path.join(bin_dir, "python3"))
    env["PATH"] = bin_dir + os.pathsep + env.get("PATH", "")
    env["OMPI_MCA_rmaps_base_oversubscribe"] = "1"
    if os.geteuid() == 0:
        env["OMPI_ALLOW_RUN_AS_ROOT"] = "1"
        env["OMPI_ALLOW_RUN_AS_ROOT_CONFIRM"] = "1"
    return env


def adapt(text):
    """The page's commands with this interpreter for 'python3'."""
    return re.sub(r"(^|[\s;&|(])python3(?=\s)", r"\1" + sys.executable, text,
                  flags=re.M)


def reduce(values, how):
    if how == "max":
        return max(values)
    if how == "min":
        return min(values)
    if how == "last":
        return values[-1]
    if how == "maxabs":
        return max(abs(v) for v in values)
    raise SystemExit("unknown reducer '%s' (max, min, last, maxabs)" % how)


def read_column(path, column):
    """The values of one column of a femp CSV file (femp_post.read_csv)."""
    table = femp_post.read_csv(path)
    if column not in table:
        raise SystemExit("%s has no column '%s' (it has %s)"
                         % (path, column, ", ".join(table)))
    values = [float(v) for v in table[column].tolist()]
    if not values:
        raise SystemExit("%s has no rows" % path)
    return values


def resolve(path):
    if "*" in path:
        matches = sorted(glob.glob(path))
        if not matches:
            raise SystemExit("no file matches %s" % path)
        return matches[-1]
    return path


def check(words, log):
    """One check; returns the line it prints, raises SystemExit on failure."""
    kind = words.split()[0]
    if kind == "log":
        regex = words[len("log"):].strip()
        if not re.search(regex, log, re.M):
            raise SystemExit("FAIL log: no line matches %r" % regex)
        return "ok   log %s" % regex
    parts = words.split()
    if kind == "file":
        path = resolve(parts[1])
        if not os.path.isfile(path) or os.path.getsize(path) == 0:
            raise SystemExit("FAIL file: %s missing or empty" % path)
        return "ok   file %s (%d bytes)" % (path, os.path.getsize(path))
    if kind == "same":
        a, b = resolve(parts[1]), resolve(parts[2])
        if not filecmp.cmp(a, b, shallow=False):
            raise SystemExit("FAIL same: %s and %s differ" % (a, b))
        return "ok   same %s %s" % (a, b)
    if kind == "csv":
        path, column, how = resolve(parts[1]), parts[2], parts[3]
        expected, tol = float(parts[4]), float(parts[5])
        got = reduce(read_column(path, column), how)
        rel = abs(got - expected) / abs(expected) if expected != 0 else abs(got)
        line = "%s csv %s %s of %s = %.6g, page %.6g, relative difference %.3g (tolerance %g)" % (
            "ok  " if rel <= tol else "FAIL", path, how, column, got, expected, rel, tol)
        if rel > tol:
            raise SystemExit(line)
        return line
    raise SystemExit("unknown check '%s'" % kind)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("page")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--work", required=False)
    ap.add_argument("--list", action="store_true",
                    help="print the blocks and checks, run nothing")
    a = ap.parse_args()
    steps = parse(a.page)
    if not any(k == "run" for k, _ in steps):
        sys.exit("%s marks no block with <!-- run -->" % a.page)
    if a.list:
        for kind, text in steps:
            print("%s: %s" % (kind, adapt(text).rstrip() if kind == "run" else text))
        return
    if not a.work:
        sys.exit("--work DIR is needed to run")
    work = os.path.abspath(a.work)
    if os.path.isdir(work):
        shutil.rmtree(work)
    os.makedirs(work)
    for d in ("prm", "contrib", "doc"):
        os.symlink(os.path.join(ROOT, d), os.path.join(work, d))
    os.symlink(os.path.abspath(a.build), os.path.join(work, "build"))
    log = ""
    start = time.time()
    for n, (kind, text) in enumerate(steps):
        if kind == "run":
            cmd = adapt(text)
            print("--- block %d:\n%s" % (n, cmd.rstrip()), flush=True)
            t0 = time.time()
            p = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", cmd], cwd=work,
                               env=block_env(work),
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               universal_newlines=True)
            log += p.stdout
            with open(os.path.join(work, "block_%02d.log" % n), "w") as f:
                f.write(p.stdout)
            tail = p.stdout.splitlines()[-8:]
            print("\n".join("    " + l for l in tail))
            print("    (exit %d, %.1f s)" % (p.returncode, time.time() - t0), flush=True)
            if p.returncode != 0:
                sys.exit("FAIL: block %d exited with %d" % (n, p.returncode))
        else:
            cwd = os.getcwd()
            os.chdir(work)
            try:
                print(check(text, log), flush=True)
            finally:
                os.chdir(cwd)
    print("all blocks ran and all checks passed (%.1f s)" % (time.time() - start))


if __name__ == "__main__":
    main()
