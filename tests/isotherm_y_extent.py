#!/usr/bin/env python3
"""contrib/validate.py's isotherm_y_extent(), the numpy copy of femp's
isotherm box (measure_melt_pool, source/heat/melt_pool.cc) that
'validate.py width' reads the near-beam width with, against femp itself,
on three scenes with a field output every 10 us and a row of
melt_pool.csv every step:

  conduction  the scene of 'validate.py pipeline' (Trapp 48 W, thermal
              only, 16 um cells, 0.2 ms), with a detached body of metal in
              the gas beside the track, part above the liquidus: the
              crossings at the surface set both widths, and the body,
              which femp leaves out, would widen the box;
  groove      the same with two grooves along the track a cell wide just
              beyond the liquidus: the liquidus box is set by the surface
              pass's face towards gas, its top cells outside the pool at
              their centres;
  depression  Trapp 65 W with the melt flow and the recoil on the compact
              domain (8 um cells, 0.3 ms): the recoil digs a depression
              and throws melt onto the plate, and the liquidus box (all
              the metal) is set by crossings below the surface and by
              faces towards gas.

On each field output, from 'Melt pool from x' on (x_min), the y-extent of
the isotherm box must give melt_pool.csv's width_solidus_substrate (the
solidus below z_top = Substrate top) and width (the liquidus in all the
metal, z_top = inf) at that time to --tolerance (m, default 1e-11: the
field output's 32-bit floats and the CSV's 8 digits; where a metal cell's
T rounds to T_iso in 32 bits, the reading with it below T_iso may match
instead); the largest difference is printed, and per width the branches
of the box that set its two ends (interior/surface pass; 'cross'
interpolated towards colder metal, 'gas' the face towards gas, 'boundary'
the domain's face, 'centre' the cell centre). Each scene must exercise
its branches (above) on at least --min-branch widths, so that the
comparison covers them. Needs numpy.

  tests/isotherm_y_extent.py --build build --out DIR [--tolerance 1e-11]
                             [--scenes conduction,groove,depression]
"""
import argparse
import collections
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "contrib"))
import femp_post  # noqa: E402
import numpy as np  # noqa: E402
import validate  # noqa: E402


def scenes():
    """name: (case, compact domain, end time s, femp parameters, the
    branches that must set or change at least --min-branch widths)."""
    thermal = {"Physics/Melt flow": "false",
               "Background grid/Cell size": "16e-6",
               "Material points/Point spacing": "8e-6"}
    g = validate.track_geometry(
        [c for c in validate.cases() if c["name"] == "trapp_048W"][0])
    L, W, top = g["Lx"], g["Ly"], g["Hp"]     # the plate, its top (m)
    box = "solid box: %g, %g, %g -> %g, %g, %g : %g"
    return {
        # with a body of metal in the gas beside the track, one cell above
        # the plate: two cells across at 3000 K beside one at 300 K, two
        # cells long, so that its hot cells touch colder metal
        "conduction": ("trapp_048W", False, 2e-4, dict(thermal, **{
            "Material points/Initial bodies": "; ".join((
                box % (160e-6, 192e-6, top + 16e-6,
                       192e-6, 224e-6, top + 32e-6, 3000),
                box % (160e-6, 224e-6, top + 16e-6,
                       192e-6, 240e-6, top + 32e-6, 300)))}),
         ("detached metal",)),
        # the plate's top row of cells a body on a substrate one row lower,
        # cut by two grooves a cell wide along the track, 40-56 um from its
        # axis: the liquidus reaches the grooves' walls at the surface only
        "groove": ("trapp_048W", False, 2e-4, dict(thermal, **{
            "Material points/Substrate top": validate.fmt(top - 16e-6),
            "Material points/Initial bodies": "; ".join(
                box % (0, y0, top - 16e-6, L, y1, top, 293.15)
                for y0, y1 in ((0, 64e-6), (80e-6, 160e-6), (176e-6, W)))}),
         ("surface gas alone",)),
        "depression": ("trapp_065W", True, 3e-4, {},
                       ("interior cross", "gas face")),
    }


def compare(name, build, out_dir):
    """Run scene @p name and compare isotherm_y_extent() with its
    melt_pool.csv: (largest difference m, widths of a pool compared,
    Counter of the branches that set an end of a width of a pool)."""
    case, compact, t_end, extra, _ = scenes()[name]
    c = [c for c in validate.cases() if c["name"] == case][0]
    d = os.path.abspath(os.path.join(out_dir, name))
    os.makedirs(d, exist_ok=True)
    scene = os.path.join(d, "scene.prm")
    open(scene, "w").write(validate.scene_text(c, compact=compact).replace(
        "include ../materials/",
        "include %s/prm/materials/" % validate.ROOT))
    x_from = validate.track_geometry(c, compact)["start"] + c["v"] * t_end / 3
    out = os.path.join(d, "output")
    sets = dict(extra)
    sets.update({"Time stepping/End time": str(t_end),
                 "Output/Directory": out,
                 # a melt_pool.csv row every step: one at each field output
                 "Output/Time series interval": "0",
                 "Output/Output interval": "1e-5",
                 "Output/Melt pool from x": validate.fmt(x_from)})

    class Ranks:
        np = 1
    exe = os.path.abspath(os.path.join(build, "femp"))
    rc, _, _ = validate.run_timed(validate.femp_cmd(Ranks, exe, sets, scene),
                                  d, os.path.join(d, "log.txt"))
    if rc != 0:
        raise SystemExit("femp failed (exit %d), see %s/log.txt" % (rc, d))

    run = femp_post.Run(out)
    pool = run.melt_pool()
    h = validate.cell_size(open(scene).read(),
                           open(os.path.join(d, "log.txt")).read())
    z_top = float(sets.get("Material points/Substrate top",
                           validate.scene_value(open(scene).read(),
                                                "Substrate top")[0]))
    mat = validate.material(c["alloy"])
    worst, compared, branches = 0.0, 0, collections.Counter()
    ambiguous = []
    for n, t in run.outputs():
        rows = [i for i, tp in enumerate(pool["time"])
                if abs(tp - t) <= 1e-7 * t]    # the CSV's 8 digits
        if not rows:
            continue
        T, A = validate.cell_arrays(run.grid(n), h, ("T", "alpha"))
        # width_solidus_substrate: the solidus below the substrate top;
        # width: the liquidus in all the metal (no top).
        for column, T_iso, top in (("width_solidus_substrate", mat["Ts"], z_top),
                                   ("width", mat["Tl"], math.inf)):
            csv = float(pool[column][rows[0]])
            why = {}
            b = validate.isotherm_y_extent(T, A, h, T_iso, top, x_from, why)
            w = b[1] - b[0] if b else 0.0
            # A metal cell whose T rounds to T_iso in 32 bits may lie on
            # either side of it in femp's doubles: then the reading with
            # those cells below T_iso (T_iso raised by one 32-bit step,
            # which moves a crossing by some 1e-13 m) may match instead.
            at = (A > 0) & (T == np.float32(T_iso))
            note = ""
            if at.any():
                up = float(np.nextafter(np.float32(T_iso), np.float32(np.inf)))
                why2 = {}
                b2 = validate.isotherm_y_extent(T, A, h, up, top, x_from, why2)
                w2 = b2[1] - b2[0] if b2 else 0.0
                note = (" [%d cells at T_iso in 32 bits; read above it: "
                        "%.4f um]" % (at.sum(), w * 1e6))
                if abs(w2 - csv) < abs(w - csv):
                    w, why, T_iso = w2, why2, up
                    ambiguous.append((name, t, column))
            ends = " | ".join(",".join(sorted(why.get(e, ()))) or "-"
                              for e in ("lo", "hi"))
            # the detached body would widen the box (femp leaves it out)
            b3 = validate.isotherm_y_extent(T, A, h, T_iso, top, x_from,
                                            detached=True)
            if (b3[1] - b3[0] if b3 else 0.0) > w + 1e-9:
                branches["detached metal"] += 1
            print("%s t = %.0f us, %s: melt_pool.csv %.4f um, "
                  "isotherm_y_extent %.4f um (%s)%s"
                  % (name, t * 1e6, column, csv * 1e6, w * 1e6, ends, note))
            worst = max(worst, abs(w - csv))
            if csv > 0:
                compared += 1
                set_by = set(why["lo"]) | set(why["hi"])
                branches.update(set_by)
                # a face towards gas in either pass; an end that only the
                # surface pass's face towards gas sets
                branches["gas face"] += any(k.endswith(" gas") for k in set_by)
                branches["surface gas alone"] += {"surface gas"} in (
                    why["lo"], why["hi"])
    print("%s: widths of a pool compared: %d; largest difference %.1e m; "
          "widths with an end set by: %s; read with the cells at T_iso "
          "below it: %d; widths that detached metal would widen: %d"
          % (name, compared, worst,
             ", ".join("%s %d" % kv for kv in sorted(branches.items())
                       if kv[0] != "detached metal"),
             len(ambiguous), branches["detached metal"]))
    return worst, compared, branches


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--build", default="build")
    p.add_argument("--out", default="build/isotherm_y_extent")
    # The field output holds T and alpha in 32-bit floats (T to about
    # 1e-4 K), melt_pool.csv the width to 8 digits: a crossing moves by
    # h dT / (T - T_neighbour), some 1e-12 m here.
    p.add_argument("--tolerance", type=float, default=1e-11,
                   help="largest difference allowed (m)")
    p.add_argument("--scenes", default="conduction,groove,depression")
    p.add_argument("--min-branch", type=int, default=3,
                   help="widths that each branch a scene exercises must set "
                   "an end of (detached metal: widen)")
    args = p.parse_args()

    failed = []
    for name in args.scenes.split(","):
        worst, compared, branches = compare(name, args.build, args.out)
        if compared < 6:
            failed.append("%s: fewer than 6 widths of a pool to compare"
                          % name)
        if not worst <= args.tolerance:
            failed.append("%s: isotherm_y_extent differs from melt_pool.csv "
                          "by %.1e m (tolerance %.0e m)"
                          % (name, worst, args.tolerance))
        for branch in scenes()[name][4]:
            if branches[branch] < args.min_branch:
                failed.append("%s: %s at %d widths, fewer than %d"
                              % (name, branch, branches[branch],
                                 args.min_branch))
    if failed:
        raise SystemExit("\n".join(failed))
    print("isotherm_y_extent agrees with melt_pool.csv")


if __name__ == "__main__":
    main()
