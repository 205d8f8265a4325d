#!/usr/bin/python3
"""femp contrib: plots of the melt-flow verification (doc/flow.md) from the
outputs of the test programs (tests/*.output or fresh runs).

Usage: contrib/flow_plots.py OUTDIR DAM_BREAK_OUTPUT [DAM_BREAK_OUTPUT_2 ...]
                             --cavity CAVITY_OUTPUT
                             [--droplet SERIES_CSV [SERIES_CSV ...]]
Each dam-break output is labelled with its file name. Droplet series come
from build/tests/test_oscillating_droplet FRACTION R/h FILE.csv (shape
measure S/S0 over t/T, T the analytic period of the 2D mode-2 oscillation);
the plot shows them with the analytic exp(-gamma t) cos(2 pi t/T).

Each dam-break output is labelled with its file name, or with LABEL when
given as PATH:LABEL. The band around the experiment is the 10 % target.
The printed lines and the series are read by contrib/femp_post.py."""
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import femp_post  # noqa: E402


def _rows(table, *columns):
    return list(zip(*(table[c].tolist() for c in columns)))


def parse_dam_break(path):
    """(T, experiment, femp) of the front and of the column height, from
    the dam-break test's printed lines."""
    front = femp_post.read_printed(
        path, r"^front Z at T = (?P<T>[\d.]+) \(experiment (?P<exp>[\d.]+)\) "
        r"= (?P<femp>[\d.]+)")
    height = femp_post.read_printed(
        path, r"^height H at t sqrt\(g/a\) = (?P<T>[\d.]+) \(experiment "
        r"(?P<exp>[\d.]+)\) = (?P<femp>[\d.]+)")
    return (_rows(front, "T", "exp", "femp"),
            _rows(height, "T", "exp", "femp"))


def parse_cavity(path):
    """(zeta, analytic, femp) of the return-flow profile."""
    t = femp_post.read_printed(
        path, r"^u/U_s at zeta = (?P<zeta>[\d.]+) \(analytic (?P<exact>[-\d.]+)\) "
        r"= (?P<femp>[-\d.]+)")
    return _rows(t, "zeta", "exact", "femp")


def plot_droplet(outdir, paths):
    import numpy as np

    fig, ax = plt.subplots(figsize=(7, 4))
    gamma_T = None
    for path in paths:
        d = femp_post.read_csv(path)
        header = d.header[0] if d.header else ""
        m = re.search(r"R/h = ([\d.]+), capillary step fraction ([\d.]+).*gamma T = ([\d.eE+-]+)", header)
        label = "femp R = %s h, step %s x capillary limit" % (m.group(1), m.group(2)) if m else path
        k = re.search(r"point shifting ([\d.]+), curvature smoothing (\d+)", header)
        if k:
            label += ", A = %s, %s smoothing passes" % (k.group(1), k.group(2))
        if m:
            gamma_T = float(m.group(3))
        ax.plot(d["t/T_exact"], d["S/S0"], "-", label=label)
    t = np.linspace(0, 1.5, 301)
    g = gamma_T if gamma_T is not None else 0.0
    ax.plot(t, np.exp(-g * t) * np.cos(2 * np.pi * t), "k:", label="analytic, 2D mode 2 (damped)")
    ax.set_xlabel("t / T,  T = 2 pi / sqrt(6 sigma/(rho R^3) - gamma^2)")
    ax.set_ylabel("shape measure S / S0")
    ax.grid(True)
    ax.legend(fontsize=8)
    ax.set_title("Oscillating droplet (2D, mode 2)")
    fig.tight_layout()
    fig.savefig(outdir + "/oscillating_droplet.png", dpi=100)


def main():
    args = sys.argv[1:]
    outdir = args.pop(0)
    cavity = None
    if "--cavity" in args:
        i = args.index("--cavity")
        cavity = args[i + 1]
        del args[i : i + 2]
    droplet = []
    if "--droplet" in args:
        i = args.index("--droplet")
        j = i + 1
        while j < len(args) and not args[j].startswith("--"):
            j += 1
        droplet = args[i + 1 : j]
        del args[i:j]
    if droplet:
        plot_droplet(outdir, droplet)
    if not args:
        return
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    first = True
    for path in args:
        path, _, label = path.partition(":")
        front, height = parse_dam_break(path)
        label = label or path.split("/")[-1]
        if first:
            ax[0].plot([f[0] for f in front], [f[1] for f in front], "ko", label="Martin & Moyce 1952")
            ax[1].plot([h[0] for h in height], [h[1] for h in height], "ko", label="Martin & Moyce 1952")
            for a, data in ((ax[0], front), (ax[1], height)):
                a.fill_between([d[0] for d in data], [0.9 * d[1] for d in data],
                               [1.1 * d[1] for d in data], color="0.85", label="experiment +-10 %")
            T = [0, 3.5]
            ax[0].plot(T, [1 + 2 * t for t in T], "k:", label="Ritter front 1 + 2T")
            first = False
        ax[0].plot([f[0] for f in front], [f[2] for f in front], "-", label="femp " + label)
        ax[1].plot([h[0] for h in height], [h[2] for h in height], "-", label="femp " + label)
    ax[0].set_xlabel("T = t sqrt(2g/a)")
    ax[0].set_ylabel("front Z = z/a")
    ax[1].set_xlabel("t sqrt(g/a)")
    ax[1].set_ylabel("column height H = h/(2a)")
    for a in ax:
        a.grid(True)
        a.legend(fontsize=8)
    fig.suptitle("Dam break (2D), femp incompressible MPM")
    fig.tight_layout()
    fig.savefig(outdir + "/dam_break.png", dpi=100)

    if cavity:
        rows = parse_cavity(cavity)
        fig, ax = plt.subplots(figsize=(5, 4))
        import numpy as np

        z = np.linspace(0, 1, 101)
        ax.plot(3 * z**2 - 2 * z, z, "k-", label="analytic (3 zeta^2 - 2 zeta)")
        ax.plot([r[2] for r in rows], [r[0] for r in rows], "o", label="femp, D = 8 h")
        ax.set_xlabel("u / U_s")
        ax.set_ylabel("zeta = z / D")
        ax.grid(True)
        ax.legend(fontsize=8)
        ax.set_title("Thermocapillary return flow, mid-length")
        fig.tight_layout()
        fig.savefig(outdir + "/thermocapillary_cavity.png", dpi=100)


if __name__ == "__main__":
    main()
