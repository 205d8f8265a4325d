#!/usr/bin/env python3
"""Compare femp runs of one scene with different laser absorption models
(doc/absorption.md): for each output directory, the medians over t > t0 of
the fusion zone in the substrate (melt_pool.csv: width_solidus_substrate,
depth_solidus_substrate), of the peak temperature T_max, and, where the run
wrote absorption.csv ('Laser/Absorption model = ray traced'), the median and
range of the absorbed fraction.

  contrib/absorption_compare.py [--after 5e-5] DIR [DIR ...]
"""
import argparse
import csv
import os
import statistics
import sys


def rows(path):
    with open(path) as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--after", type=float, default=5e-5,
                    help="medians over t > this time, s (default 5e-5)")
    a = ap.parse_args()
    print("| run | fusion zone width (um) | depth (um) | T_max (K) "
          "| absorbed fraction median [min, max] |")
    print("|---|---:|---:|---:|---|")
    for d in a.dirs:
        pool = [r for r in rows(os.path.join(d, "melt_pool.csv"))
                if r["time"] > a.after]
        if not pool:
            sys.exit(f"{d}: no melt_pool.csv rows after {a.after} s")
        med = lambda key: statistics.median(r[key] for r in pool)
        frac = "fixed (Absorptivity)"
        ab = os.path.join(d, "absorption.csv")
        if os.path.exists(ab):
            f = [r["absorbed_fraction"] for r in rows(ab)
                 if r["time"] > a.after and r["incident"] > 0]
            if f:
                frac = (f"{statistics.median(f):.3f} "
                        f"[{min(f):.3f}, {max(f):.3f}]")
        print(f"| {d} | {1e6 * med('width_solidus_substrate'):.1f} "
              f"| {1e6 * med('depth_solidus_substrate'):.1f} "
              f"| {med('T_max'):.0f} | {frac} |")


if __name__ == "__main__":
    main()
