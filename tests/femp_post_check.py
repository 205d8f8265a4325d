#!/usr/bin/env python3
# Test of contrib/femp_post.py (tests/run_render_test.cmake): the same run of
# tests/render_tiny.prm written as VTU (directory VTU) and as HDF5 (directory
# HDF5) must load into the same arrays: the output times, every grid field
# of every output (cells matched by their centres), the points' temperature
# (matched by id), the probe line and the melt-pool series. Fails on any
# difference above 1e-6 relative (both formats store 4-byte floats).
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "contrib"))
import femp_post  # noqa: E402


def same(what, a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    scale = max(1e-300, np.abs(a).max() if a.size else 1)
    err = np.abs(a - b).max() / scale if a.size else 0.0
    ok = a.shape == b.shape and err <= 1e-6
    print("%-40s %8d values, max relative difference %.1e %s"
          % (what, a.size, err, "ok" if ok else "FAILED"))
    return ok


def main(vtu_dir, hdf5_dir):
    v, h = femp_post.Run(vtu_dir), femp_post.Run(hdf5_dir)
    assert v.format == "vtu" and h.format == "hdf5", (v.format, h.format)
    ok = same("grid output times", [t for _, t in v.outputs()],
              [t for _, t in h.outputs()])
    for n, t in v.outputs():
        gv, gh = v.grid(n), h.grid(n)
        order_v = np.lexsort(np.round(gv.centres, 9).T[::-1])
        order_h = np.lexsort(np.round(gh.centres, 9).T[::-1])
        ok &= same("grid %d: cell centres" % n, gv.centres[order_v],
                   gh.centres[order_h])
        for name in sorted(set(gv) & set(gh)):
            ok &= same("grid %d: %s" % (n, name), gv[name][order_v],
                       gh[name][order_h])
        if len(set(gv) & set(gh)) < 5:
            print("grid %d: too few common fields" % n)
            ok = False
    pv, ph = v.points(), h.points()
    iv, ih = np.argsort(pv["id"]), np.argsort(ph["id"])
    ok &= same("points: id", pv["id"][iv], ph["id"][ih])
    ok &= same("points: temperature", pv["temperature"][iv],
               ph["temperature"][ih])
    ok &= same("points: von Mises", femp_post.von_mises(pv)[iv],
               femp_post.von_mises(ph)[ih])
    for name in v.probe_line_names():
        lv, lh = v.probe_line(name), h.probe_line(name)
        ok &= lv.time == lh.time and lv.time is not None
        ok &= same("probe line %s: T" % name, lv["T"], lh["T"])
    ok &= same("melt_pool.csv: T_max", v.melt_pool()["T_max"],
               h.melt_pool()["T_max"])
    print("femp_post:", "all equal" if ok else "DIFFERENCES")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
