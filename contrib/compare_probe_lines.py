#!/usr/bin/env python3
"""Compare the probe lines of two femp runs of the same scene.

For each probe line and column, prints the largest difference between the
two runs over the samples in full cells (alpha >= --alpha, default 0.95 in
both runs), relative to the reference run's peak there: |value| for
stresses, value - T0 for the temperature (T0 = --t0, default 300 K).

    python3 contrib/compare_probe_lines.py REF_DIR OTHER_DIR [--output N]
        [--lines CD,EF] [--columns sigma_xx,von_mises,T]

--output N compares probe_line_<name>_<N>.csv (default: the last output of
each run, which for a run stopped by 'Stop when peak temperature below'
may lie at a slightly different time; the files' '# time' lines are
printed). Standard library only.
"""
import argparse
import csv
import glob
import os
import sys


def read(path):
    """Columns of a femp probe-line CSV and its '# time = ...' header."""
    time = None
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                if "time" in line:
                    time = line.strip("# \n")
                continue
            rows.append(line)
    cols = {}
    for r in csv.DictReader(rows):
        for k, v in r.items():
            cols.setdefault(k.strip(), []).append(float(v))
    return cols, time


def probe_file(directory, line, n):
    if n is not None:
        return os.path.join(directory, "probe_line_%s_%05d.csv" % (line, n))
    files = sorted(glob.glob(os.path.join(directory, "probe_line_%s_*.csv" % line)))
    if not files:
        sys.exit("no probe line %s in %s" % (line, directory))
    return files[-1]


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("reference")
    ap.add_argument("other")
    ap.add_argument("--output", type=int, default=None)
    ap.add_argument("--lines", default=None,
                    help="comma-separated names (default: all of the reference)")
    ap.add_argument("--columns", default="sigma_xx,von_mises,T")
    ap.add_argument("--alpha", type=float, default=0.95)
    ap.add_argument("--t0", type=float, default=300.0)
    a = ap.parse_args()
    if a.lines:
        lines = a.lines.split(",")
    else:
        names = glob.glob(os.path.join(a.reference, "probe_line_*_00000.csv"))
        lines = sorted(os.path.basename(f)[len("probe_line_"):-len("_00000.csv")]
                       for f in names)
    print("line,column,peak,largest_difference,relative,samples,time_reference,time_other")
    for line in lines:
        ref, t_ref = read(probe_file(a.reference, line, a.output))
        oth, t_oth = read(probe_file(a.other, line, a.output))
        for col in a.columns.split(","):
            if col not in ref or col not in oth:
                continue
            keep = [i for i in range(len(ref[col]))
                    if ref["alpha"][i] >= a.alpha and oth["alpha"][i] >= a.alpha]
            if not keep:
                continue
            offset = a.t0 if col == "T" else 0.0
            peak = max(abs(ref[col][i] - offset) for i in keep)
            diff = max(abs(ref[col][i] - oth[col][i]) for i in keep)
            print("%s,%s,%.4g,%.4g,%.3f,%d,%s,%s" % (
                line, col, peak, diff, diff / peak if peak > 0 else 0.0,
                len(keep), t_ref, t_oth))


if __name__ == "__main__":
    main()
