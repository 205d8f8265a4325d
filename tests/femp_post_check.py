#!/usr/bin/env python3
# Test of contrib/femp_post.py (tests/run_render_test.cmake): the same run of
# tests/render_tiny.prm written as VTU (directory VTU) and as HDF5 (directory
# HDF5) must load into the same arrays: the output times, every grid field
# of every output (cells matched by their centres), the points' temperature
# (matched by id), the probe line, the melt-pool series and the solid's
# energy accounts. Fails on any difference above 1e-6 relative (both
# formats store 4-byte floats). Then the readers of text: read_printed on
# a known text and on the two runs' logs (femp_<format>.log beside the
# directories: the same progress lines, the last at the end time; the
# solid's printed report against its energy file), read_parameters on a
# known file and on the scene against the parameters.prm of the run, and
# the CSV reader without numpy (the same values as lists).
import os
import sys
import tempfile

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
    ev, eh = v.solid_energy(), h.solid_energy()
    for name in ("time", "internal_work", "balance"):
        ok &= same("solid_energy.csv: %s" % name, ev[name], eh[name])
    ok &= text_readers(v, h, vtu_dir, hdf5_dir)
    print("femp_post:", "all equal" if ok else "DIFFERENCES")
    return 0 if ok else 1


def check(what, ok):
    print("%-40s %s" % (what, "ok" if ok else "FAILED"))
    return ok


PROGRESS = r"^t =\s*(?P<t>[0-9.eE+-]+) s\s+step\s+(?P<step>\d+)"


def text_readers(v, h, vtu_dir, hdf5_dir):
    ok = True
    # read_printed on a known text: named and numbered groups, a group that
    # does not take part, the lines of the rows
    text = ("femp\nt = 1e-06 s  step 10 x\nnoise t = 3 s step 1\n"
            "t = 2.5e-06 s  step 25 y\n")
    p = femp_post.read_printed(text, PROGRESS)
    ok &= check("read_printed: named groups",
                p["t"].tolist() == [1e-6, 2.5e-6] and
                p["step"].tolist() == [10, 25] and p.lines.tolist() == [1, 3])
    q = femp_post.read_printed(text.split("\n"), r"step (\d+)( x)?")
    ok &= check("read_printed: numbered groups",
                q["1"].tolist() == [10, 1, 25] and
                q["2"].tolist() == [" x", "", ""])
    # the two runs print the same progress lines, the last at the end time
    logs = [os.path.join(os.path.dirname(os.path.abspath(d)),
                         "femp_%s.log" % f)
            for d, f in ((vtu_dir, "vtu"), (hdf5_dir, "hdf5"))]
    if all(os.path.exists(x) for x in logs):
        a, b = (femp_post.read_printed(x, PROGRESS) for x in logs)
        end = float(v.parameter("Time stepping/End time"))
        ok &= check("read_printed: progress lines of the logs",
                    len(a) >= 1 and a["t"].tolist() == b["t"].tolist() and
                    a["step"].tolist() == b["step"].tolist() and
                    abs(a["t"][-1] - end) <= 1e-9 * end)
        # the solid's end report against the last row of its energy file
        s = femp_post.read_printed(
            logs[0], r"^Solid: (?P<steps>\d+) steps of .* stress work "
            r"(?P<work>[-+0-9.eE]+), .* balance (?P<balance>[-+0-9.eE]+)")
        e = v.solid_energy()
        ok &= check("read_printed: the solid's report = CSV",
                    len(s) == 1 and s["steps"][0] == e["step"][-1] and
                    abs(s["work"][0] - e["internal_work"][-1]) <=
                    1e-5 * abs(e["internal_work"][-1]) and
                    abs(s["balance"][0] - e["balance"][-1]) <=
                    1e-5 * abs(e["balance"][-1]))
    else:
        ok &= check("the logs femp_vtu.log and femp_hdf5.log", False)
    # read_parameters: sections, comments, an entry set twice
    with tempfile.TemporaryDirectory() as tmp:
        f = os.path.join(tmp, "x.prm")
        with open(f, "w") as out:
            out.write("set Dimension = 3 # a comment\nsubsection A\n"
                      "  subsection B\n    set Name = 1, 2\n  end\n"
                      "  set Name = x\n  set Name = y\nend\n")
        ok &= check("read_parameters: a known file",
                    femp_post.read_parameters(f) ==
                    {"Dimension": "3", "A/B/Name": "1, 2", "A/Name": "y"})
    scene = femp_post.read_parameters(
        os.path.join(os.path.dirname(os.path.abspath(__file__)),
                     "render_tiny.prm"))
    for name in ("Background grid/Cell size", "Laser/Power",
                 "Material points/Substrate top"):
        ok &= check("Run.parameter: %s" % name,
                    float(v.parameter(name)) == float(scene[name]) and
                    float(h.parameter(name.split("/")[-1])) ==
                    float(scene[name]))
    # without numpy: the same CSV values as lists
    np_saved = femp_post.np
    try:
        femp_post.np = None
        pool = v.melt_pool()
        plain = isinstance(pool["T_max"], femp_post.Column)
        values = pool["T_max"].tolist()
        last = pool["time"][-2:].tolist()
    finally:
        femp_post.np = np_saved
    pool = v.melt_pool()
    ok &= check("read_csv without numpy",
                plain and values == pool["T_max"].tolist() and
                last == pool["time"][-2:].tolist())
    return ok


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
