#!/usr/bin/env python3
"""contrib/validate.py's isotherm_y_extent(), the numpy copy of femp's
isotherm box (measure_melt_pool, source/heat/melt_pool.cc) that
'validate.py width' reads the near-beam width with, against femp itself:
the scene of 'validate.py pipeline' (Trapp 48 W, thermal only, 16 um
cells, 0.2 ms; the pool measured from a third of the track on, 'Output/Melt
pool from x') with a field output every 10 us and a row of melt_pool.csv
every step. On each field output with a pool, from 'Melt pool from x' on
(x_min), the y-extent of the isotherm box must give melt_pool.csv's
width_solidus_substrate (the solidus below z_top = Substrate top) and
width (the liquidus in all the metal, z_top = inf) at that time to
--tolerance (m, default 1e-11: the field output's 32-bit floats and the
CSV's 8 digits); the largest difference is printed. In this conduction
pool the surface crossings set both widths. Needs numpy.

  tests/isotherm_y_extent.py --build build --out DIR [--tolerance 1e-11]
"""
import argparse
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "contrib"))
import femp_post  # noqa: E402
import validate  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--build", default="build")
    p.add_argument("--out", default="build/isotherm_y_extent")
    # The field output holds T and alpha in 32-bit floats (T to about
    # 1e-4 K), melt_pool.csv the width to 8 digits: a crossing moves by
    # h dT / (T - T_neighbour), some 1e-12 m here.
    p.add_argument("--tolerance", type=float, default=1e-11,
                   help="largest difference allowed (m)")
    args = p.parse_args()

    c = [c for c in validate.cases() if c["name"] == "trapp_048W"][0]
    d = os.path.abspath(args.out)
    os.makedirs(d, exist_ok=True)
    scene = os.path.join(d, "scene.prm")
    open(scene, "w").write(validate.scene_text(c).replace(
        "include ../materials/",
        "include %s/prm/materials/" % validate.ROOT))
    t_end = 2e-4
    x_from = validate.track_geometry(c)["start"] + c["v"] * t_end / 3
    out = os.path.join(d, "output")
    sets = {"Physics/Melt flow": "false", "Background grid/Cell size": "16e-6",
            "Material points/Point spacing": "8e-6",
            "Time stepping/End time": str(t_end),
            "Output/Directory": out,
            # a melt_pool.csv row every step: one at each field output
            "Output/Time series interval": "0",
            "Output/Output interval": "1e-5",
            "Output/Melt pool from x": validate.fmt(x_from)}
    args.np = 1
    exe = os.path.abspath(os.path.join(args.build, "femp"))
    rc, _, _ = validate.run_timed(validate.femp_cmd(args, exe, sets, scene),
                                  d, os.path.join(d, "log.txt"))
    if rc != 0:
        raise SystemExit("femp failed (exit %d), see %s/log.txt" % (rc, d))

    run = femp_post.Run(out)
    pool = run.melt_pool()
    h = validate.cell_size(open(scene).read(),
                           open(os.path.join(d, "log.txt")).read())
    z_top = validate.scene_value(open(scene).read(), "Substrate top")[0]
    mat = validate.material(c["alloy"])
    worst, compared = 0.0, 0
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
            b = validate.isotherm_y_extent(T, A, h, T_iso, top, x_from)
            w = b[1] - b[0] if b else 0.0
            print("t = %.0f us, %s: melt_pool.csv %.4f um, "
                  "isotherm_y_extent %.4f um"
                  % (t * 1e6, column, csv * 1e6, w * 1e6))
            worst = max(worst, abs(w - csv))
            compared += csv > 0
    print("widths of a pool compared: %d; largest difference %.1e m "
          "(tolerance %.0e m)" % (compared, worst, args.tolerance))
    if compared < 6:
        raise SystemExit("fewer than 6 widths of a pool to compare")
    if not worst <= args.tolerance:
        raise SystemExit("isotherm_y_extent differs from melt_pool.csv")
    print("isotherm_y_extent agrees with melt_pool.csv")


if __name__ == "__main__":
    main()
