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
printed). --fail-above R exits with status 1 when a relative difference
exceeds R (a check for scripts and tests). Python 3 with numpy; the files are read by contrib/femp_post.py.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import femp_post  # noqa: E402


def read(directory, line, n):
    """Columns of a probe line's output n (None: the last) and its time."""
    try:
        t = femp_post.Run(directory).probe_line(line, n)
    except FileNotFoundError as e:
        sys.exit(str(e))
    return t, "time = %.8g s" % t.time


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
    ap.add_argument("--fail-above", type=float, default=None,
                    help="exit 1 when a relative difference exceeds this")
    a = ap.parse_args()
    if a.lines:
        lines = a.lines.split(",")
    else:
        lines = femp_post.Run(a.reference).probe_line_names()
    print("line,column,peak,largest_difference,relative,samples,time_reference,time_other")
    worst = 0.0
    for line in lines:
        ref, t_ref = read(a.reference, line, a.output)
        oth, t_oth = read(a.other, line, a.output)
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
            rel = diff / peak if peak > 0 else 0.0
            worst = max(worst, rel)
            print("%s,%s,%.4g,%.4g,%.3f,%d,%s,%s" % (
                line, col, peak, diff, rel, len(keep), t_ref, t_oth))
    if a.fail_above is not None:
        if worst > a.fail_above:
            sys.exit("largest relative difference %.3g exceeds %g" % (worst, a.fail_above))
        print("largest relative difference %.3g, within %g" % (worst, a.fail_above))


if __name__ == "__main__":
    main()
