#!/usr/bin/env python3
# Test of contrib/femp_post.py probe_line_summary() (doc/builds.md, the
# probe lines of prm/multi_layer.prm): a probe line written in femp's
# format with seven samples, one of each kind: gas (alpha 0), a stressed
# cell 0.12 full, powder half full (alpha 0.5, no stress), stressed cells
# 0.86, 1 and 1 full, a stressed cell 0.3 full. The summary must count
# 7 samples, 5 stressed, 3 of them in cells at least half full, 2 in
# partly filled cells, and give over those 3 (x = 3, 4, 6 below)
# sigma_xx mean (-20 + 30 + 50) / 3 = 20, min -20, max 50 MPa and
# von Mises mean (60 + 70 + 90) / 3, min 60, max 90 MPa. Prints each
# error and fails above 1e-12 (relative).
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "contrib"))
import femp_post  # noqa: E402

ALPHA = [0, 0.12, 0.5, 0.86, 1.0, 0.3, 1.0]
SXX = [0, 10, 0, -20, 30, 40, 50]  # MPa
VM = [0, 50, 0, 60, 70, 80, 90]  # MPa


def main():
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "probe_line_gap_00001.csv")
        with open(path, "w") as f:
            f.write("# time = 0.001 s\ns,x,y,z,T,alpha,sigma_xx,von_mises\n")
            for i, (a, s, v) in enumerate(zip(ALPHA, SXX, VM)):
                f.write("%g,%g,0,0,300,%g,%g,%g\n"
                        % (i * 8e-6, i * 8e-6, a, s * 1e6, v * 1e6))
        got = femp_post.Run(d).probe_line_summary("gap")
    ok = True
    for key, want in (("samples", 7), ("stressed", 5), ("metal", 3),
                      ("partial", 2)):
        good = got[key] == want
        ok &= good
        print("%-20s %d (expected %d) %s"
              % (key, got[key], want, "ok" if good else "FAILED"))
    for field, want in (("sigma_xx", (20e6, -20e6, 50e6)),
                        ("von_mises", (220e6 / 3, 60e6, 90e6))):
        for stat, w in zip(("mean", "min", "max"), want):
            err = abs(got[field][stat] - w) / abs(w)
            good = err <= 1e-12
            ok &= good
            print("%-9s %-4s %.6g Pa, relative error %.1e %s"
                  % (field, stat, got[field][stat], err,
                     "ok" if good else "FAILED"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
