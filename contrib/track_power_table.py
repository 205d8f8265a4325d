#!/usr/bin/env python3
"""Table of melt pool, bead and stresses against the laser power for track
runs (the paper's case 3.3), with the Python standard library only.

    python3 contrib/track_power_table.py --n N DIR=label ...

reads from each output directory DIR melt_pool.csv, track_bead.csv and
probe_line_CD_<N>.csv (field output number N, at time t_N) and prints a
Markdown table, one row per run:
  - the melt pool's length x width x depth at t_N and the largest of each
    over the run up to t_N (um; the pool is the metal above the liquidus,
    melt_pool.csv);
  - the fusion zone in the substrate: the largest width and depth of
    substrate metal that reached the solidus, up to t_N (um);
  - the re-solidified bead at t_N: cross-section width x height at the
    track-shape section, and the centre line's length x height (um);
  - on probe line CD at t_N: the largest T (K), the sigma_xx of largest
    magnitude, the largest von Mises stress (MPa) and plastic strain (%);
    the length of CD where von Mises >= 200 MPa (um; the "high-stress
    zone") and the standard deviation of sigma_xx along CD (MPa; how much
    the stress varies along the line), both over the samples in metal
    (alpha >= 0.95);
  - from the field output N (grid_<N>.*.vtu): the volume of metal (cells
    with alpha >= 1/2) with von Mises >= 200 MPa in the substrate (cell
    centres below 'Substrate top' of the run's parameters.prm) and above
    it (um^3), the extent of the stressed zone the paper's Fig. 9 shows.
"""
import csv
import glob
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_track_svg import _decode  # noqa: E402


def rows(path):
    lines = [l for l in open(path) if not l.startswith("#")]
    return list(csv.DictReader(lines))


def parameter(path, name):
    """The value of 'set NAME = value' in a written parameters.prm."""
    for line in open(path):
        m = re.match(r"\s*set\s+%s\s*=\s*([^#]+)" % re.escape(name), line)
        if m:
            return m.group(1).strip()
    raise KeyError(name)


def stressed_volume(d, n, threshold=200e6):
    """Metal volume with von Mises >= threshold below and above the
    substrate top, m^3, from the grid output n of run d."""
    z_top = float(parameter(d + "/parameters.prm", "Substrate top"))
    h3 = float(parameter(d + "/parameters.prm", "Cell size")) ** 3
    below = above = 0.
    for piece in sorted(glob.glob("%s/grid_%05d.*.vtu" % (d, n))):
        arrays = {}
        for m in re.finditer(r'<DataArray([^>]*)>([^<]*)</DataArray>', open(piece).read()):
            attrs = m.group(1)
            name = re.search(r'Name="(\w+)"', attrs)
            name = name.group(1) if name else "points"
            if name in ("points", "alpha", "von_mises") and 'format="binary"' in attrs:
                arrays[name] = _decode(m.group(2), re.search(r'type="(\w+)"', attrs).group(1))
        pts, alpha, vm = arrays["points"], arrays["alpha"], arrays["von_mises"]
        for i in range(0, len(alpha), 8):  # 8 vertices per cell, one value
            if alpha[i] >= 0.5 and vm[i] >= threshold:
                z = sum(pts[3 * (i + k) + 2] for k in range(8)) / 8
                if z < z_top:
                    below += h3
                else:
                    above += h3
    return below, above


def main(argv):
    n = None
    runs = []
    i = 0
    while i < len(argv):
        if argv[i] == "--n":
            n = int(argv[i + 1])
            i += 2
            continue
        d, _, label = argv[i].partition("=")
        runs.append((d, label or d))
        i += 1
    if n is None or not runs:
        sys.exit(__doc__)
    print("| run | pool L x W x D at t_N (um) | largest pool L x W x D (um) "
          "| fusion zone in the substrate, largest W x D (um) "
          "| bead at t_N: cross-section W x H, centre line L x H (um) "
          "| CD at t_N: T max (K), sigma_xx of largest magnitude, von Mises max (MPa), "
          "plastic strain max | CD at t_N: length with von Mises >= 200 MPa (um), "
          "sigma_xx standard deviation (MPa) | metal with von Mises >= 200 MPa at t_N: "
          "in the substrate, above it (1000 um^3) |")
    print("|---|---|---|---|---|---|---|---|")
    um = lambda r, k: float(r[k]) * 1e6
    for d, label in runs:
        cd_path = "%s/probe_line_CD_%05d.csv" % (d, n)
        t_n = float(open(cd_path).readline().split("=")[1].split()[0])
        pool = [r for r in rows(d + "/melt_pool.csv") if float(r["time"]) <= t_n * (1 + 1e-9)]
        at = pool[-1]
        big = {k: max(um(r, k) for r in pool) for k in
               ("length", "width", "depth", "width_solidus_substrate",
                "depth_solidus_substrate")}
        bead = min(rows(d + "/track_bead.csv"), key=lambda r: abs(float(r["time"]) - t_n))
        wk = [k for k in bead if k.startswith("width_")][0]
        hk = "height_" + wk[len("width_"):]
        cd = rows(cd_path)
        mpa = [float(r["sigma_xx"]) * 1e-6 for r in cd]
        metal = [r for r in cd if float(r["alpha"]) >= 0.95]
        ds = (float(cd[1]["s"]) - float(cd[0]["s"])) * 1e6
        high = ds * sum(1 for r in metal if float(r["von_mises"]) >= 200e6)
        sx = [float(r["sigma_xx"]) * 1e-6 for r in metal]
        mean = sum(sx) / len(sx)
        std = (sum((v - mean) ** 2 for v in sx) / len(sx)) ** 0.5
        below, above = stressed_volume(d, n)
        print("| %s | %.0f x %.0f x %.0f | %.0f x %.0f x %.0f | %.0f x %.0f "
              "| %.0f x %.0f, %.0f x %.0f | %.0f, %.0f, %.0f, %.2f %% | %.0f, %.0f | %.0f, %.0f |"
              % (label, um(at, "length"), um(at, "width"), um(at, "depth"),
                 big["length"], big["width"], big["depth"],
                 big["width_solidus_substrate"], big["depth_solidus_substrate"],
                 um(bead, wk), um(bead, hk), um(bead, "centre_length"),
                 um(bead, "centre_height"),
                 max(float(r["T"]) for r in cd), max(mpa, key=abs),
                 max(float(r["von_mises"]) for r in cd) * 1e-6,
                 100 * max(float(r["plastic_strain"]) for r in cd), high, std,
                 below * 1e15, above * 1e15))


if __name__ == "__main__":
    main(sys.argv[1:])
