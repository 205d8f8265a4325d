#!/usr/bin/env python3
"""Table of melt pool, bead and stresses against the laser power for track
runs (the paper's case 3.3).

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

The files are read by contrib/femp_post.py (numpy; VTU or HDF5 output).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import femp_post  # noqa: E402


def stressed_volume(d, n, threshold=200e6):
    """Metal volume with von Mises >= threshold below and above the
    substrate top, m^3, from the grid output n of run d."""
    run = femp_post.Run(d)
    z_top = float(run.parameter("Substrate top"))
    h3 = float(run.parameter("Cell size")) ** 3
    g = run.grid(n)
    below = above = 0.
    for alpha, vm, z in zip(g["alpha"].tolist(), g["von_mises"].tolist(),
                            g.centres[:, 2].tolist()):
        if alpha >= 0.5 and vm >= threshold:
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
    for d, label in runs:
        run = femp_post.Run(d)
        cd = run.probe_line("CD", n)
        t_n = cd.time
        pool = run.melt_pool()
        keep = [i for i, t in enumerate(pool["time"].tolist())
                if t <= t_n * (1 + 1e-9)]
        um = {k: [v * 1e6 for v in pool[k].tolist()] for k in
              ("length", "width", "depth", "width_solidus_substrate",
               "depth_solidus_substrate")}
        at = {k: v[keep[-1]] for k, v in um.items()}
        big = {k: max(v[i] for i in keep) for k, v in um.items()}
        beads = run.track_bead()
        times = beads["time"].tolist()
        i_b = min(range(len(times)), key=lambda i: abs(times[i] - t_n))
        bead = {k: v[i_b] * 1e6 for k, v in beads.items()}
        wk = [k for k in beads if k.startswith("width_")][0]
        hk = "height_" + wk[len("width_"):]
        col = {k: cd[k].tolist() for k in
               ("s", "alpha", "T", "sigma_xx", "von_mises", "plastic_strain")}
        mpa = [v * 1e-6 for v in col["sigma_xx"]]
        metal = [i for i, a in enumerate(col["alpha"]) if a >= 0.95]
        ds = (col["s"][1] - col["s"][0]) * 1e6
        high = ds * sum(1 for i in metal if col["von_mises"][i] >= 200e6)
        sx = [col["sigma_xx"][i] * 1e-6 for i in metal]
        mean = sum(sx) / len(sx)
        std = (sum((v - mean) ** 2 for v in sx) / len(sx)) ** 0.5
        below, above = stressed_volume(d, n)
        print("| %s | %.0f x %.0f x %.0f | %.0f x %.0f x %.0f | %.0f x %.0f "
              "| %.0f x %.0f, %.0f x %.0f | %.0f, %.0f, %.0f, %.2f %% | %.0f, %.0f | %.0f, %.0f |"
              % (label, at["length"], at["width"], at["depth"],
                 big["length"], big["width"], big["depth"],
                 big["width_solidus_substrate"], big["depth_solidus_substrate"],
                 bead[wk], bead[hk], bead["centre_length"],
                 bead["centre_height"],
                 max(col["T"]), max(mpa, key=abs),
                 max(col["von_mises"]) * 1e-6,
                 100 * max(col["plastic_strain"]), high, std,
                 below * 1e15, above * 1e15))


if __name__ == "__main__":
    main(sys.argv[1:])
