#!/usr/bin/env python3
"""Compare femp runs of one scene with different laser absorption models
(doc/absorption.md): for each output directory, the medians over t > t0 of
the fusion zone in the substrate (melt_pool.csv: width_solidus_substrate,
depth_solidus_substrate), of the peak temperature T_max, and, where the run
wrote absorption.csv ('Laser/Absorption model = ray traced'), the median and
range of the absorbed fraction.

  contrib/absorption_compare.py [--after 5e-5] DIR [DIR ...]

The files are read by contrib/femp_post.py (numpy).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import femp_post  # noqa: E402


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
        run = femp_post.Run(d)
        pool = run.melt_pool()
        late = pool["time"] > a.after
        if not late.any():
            sys.exit(f"{d}: no melt_pool.csv rows after {a.after} s")
        med = lambda key: float(np.median(pool[key][late]))
        frac = "fixed (Absorptivity)"
        if os.path.exists(os.path.join(d, "absorption.csv")):
            ab = run.absorption()
            f = ab["absorbed_fraction"][(ab["time"] > a.after)
                                        & (ab["incident"] > 0)]
            if len(f):
                frac = (f"{np.median(f):.3f} "
                        f"[{f.min():.3f}, {f.max():.3f}]")
        print(f"| {d} | {1e6 * med('width_solidus_substrate'):.1f} "
              f"| {1e6 * med('depth_solidus_substrate'):.1f} "
              f"| {med('T_max'):.0f} | {frac} |")

if __name__ == "__main__":
    main()
