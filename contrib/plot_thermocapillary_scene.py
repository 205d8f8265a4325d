#!/usr/bin/python3
"""femp contrib: the thermocapillary cavity scene (prm/thermocapillary_cavity.prm)
against the closed-form return-flow profile (doc/verification.md)

    u(zeta) = tau_s D/(4 mu) (3 zeta^2 - 2 zeta),  tau_s = dsigma/dT G.

Usage: contrib/plot_thermocapillary_scene.py OUT.png PROBE_CSV[:LABEL] [...]
           [--floor 12.5e-6] [--depth 100e-6] [--mu 6e-3] [--dsdT -4.3e-4]
           [--G 1000]

PROBE_CSV is a probe line 'mid' written by femp (columns s, x, y, ..., u_x),
e.g. output_thermocapillary_cavity/probe_line_mid_00005.csv (the last output
of the scene, 0.05 s) or build/tests/thermocapillary_scene.mpirun=1/output/
probe_line_mid_00001.csv (the test's coarser run). The defaults are the
scene's parameters. Prints, per file, the largest pointwise error, the
surface speed (quadratic through the three top cells at zeta = 1) and the
zero crossing, as the test does. The probe lines are read by
contrib/femp_post.py."""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import femp_post  # noqa: E402


def option(args, name, default):
    if name in args:
        i = args.index(name)
        value = float(args[i + 1])
        del args[i : i + 2]
        return value
    return default


def main():
    args = sys.argv[1:]
    floor = option(args, "--floor", 12.5e-6)
    depth = option(args, "--depth", 100e-6)
    mu = option(args, "--mu", 6e-3)
    dsdT = option(args, "--dsdT", -4.3e-4)
    G = option(args, "--G", 1000.0)
    if len(args) < 2:
        print(__doc__)
        return 1
    out, files = args[0], args[1:]
    U = dsdT * G * depth / (4 * mu)
    fig, ax = plt.subplots(figsize=(5, 5))
    z = np.linspace(0, 1, 201)
    ax.plot(3 * z**2 - 2 * z, z, "k-", label="closed form (3 zeta^2 - 2 zeta)")
    for spec, marker in zip(files, "osd^v"):
        path, _, label = spec.partition(":")
        line = femp_post.read_csv(path)
        y = line["y"]
        u = line["u_x"]
        zeta = (y - floor) / depth
        keep = (zeta > 0) & (zeta < 1)
        zeta, prof = zeta[keep], u[keep] / U
        n = len(zeta)
        err = np.max(np.abs(prof - (3 * zeta**2 - 2 * zeta)))
        top = slice(n - 3, n)
        us = np.polyval(np.polyfit(zeta[top], prof[top], 2), 1.0)
        k = np.nonzero(prof[:-1] * prof[1:] <= 0)[0]
        zero = (zeta[k[0]] + (zeta[k[0] + 1] - zeta[k[0]]) * prof[k[0]]
                / (prof[k[0]] - prof[k[0] + 1])) if len(k) else float("nan")
        print("%s: %d cells, max |u - u_exact|/U_s = %.4f, surface speed/U_s = "
              "%.4f, zero crossing zeta = %.4f" % (path, n, err, us, zero))
        ax.plot(prof, zeta, marker, mfc="none",
                label=(label or "femp") + " (D = %d h)" % n)
    ax.axhline(2.0 / 3, color="0.7", lw=0.8, ls=":")
    ax.axvline(0, color="0.7", lw=0.8)
    ax.set_xlabel("u / U_s,  U_s = tau_s D/(4 mu) = %.3g m/s" % U)
    ax.set_ylabel("zeta = height above the floor / D")
    ax.set_title("Thermocapillary cavity, profile at mid-length")
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    return 0


if __name__ == "__main__":
    sys.exit(main())
