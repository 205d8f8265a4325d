#!/usr/bin/env python3
"""Verification plots for doc/verification.md.

Runs the Stefan and Rosenthal test programs of a femp build in a scratch
directory (they write CSV data beside their checks) and plots the
simulation against the closed forms:
  doc/img/stefan.png     front position and final profile vs Neumann
  doc/img/rosenthal.png  melt-pool isotherm vs Eagar-Tsai (surface, side)

Usage: /usr/bin/python3 contrib/plot_verification.py [build-dir]
Needs Debian's python3-matplotlib and python3-numpy; the CSV files are read
by contrib/femp_post.py.
"""
import os
import subprocess
import sys
import tempfile

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(root, "contrib"))
import femp_post  # noqa: E402

build = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "build"))
out_dir = os.path.join(root, "doc", "img")
os.makedirs(out_dir, exist_ok=True)


def read(path):
    return femp_post.read_csv(path)


def run(test, *args):
    exe = os.path.join(build, "tests", "test_" + test)
    subprocess.run([exe, *args], cwd=work, check=True, stdout=subprocess.DEVNULL)


work = tempfile.mkdtemp(prefix="femp_plots_")
run("stefan_two_phase")
run("rosenthal")

# Stefan: front history and final temperature profile.
front = read(os.path.join(work, "stefan_front.csv"))
prof = read(os.path.join(work, "stefan_profile.csv"))
fig, ax = plt.subplots(1, 2, figsize=(10, 4))
ax[0].plot(front["t"], front["s_exact"], "k-", label=r"closed form $2\lambda\sqrt{t}$")
ax[0].plot(front["t"][::8], front["s_sim"][::8], "o", ms=3, label="femp (h = 0.01)")
ax[0].set_xlabel("t (s)")
ax[0].set_ylabel("front position s (m)")
ax[0].set_title("Two-phase Stefan problem, lambda = 0.377760")
ax[0].legend()
mask = prof["x"] < 2.0
ax[1].plot(prof["x"][mask], prof["T_exact"][mask], "k-", label="Neumann solution")
ax[1].plot(prof["x"][mask][::4], prof["T_sim"][mask][::4], "o", ms=3, label="femp")
ax[1].set_xlabel("x (m)")
ax[1].set_ylabel("T (K)")
ax[1].set_title("Temperature at t = 1 s")
ax[1].legend()
fig.tight_layout()
fig.savefig(os.path.join(out_dir, "stefan.png"), dpi=110)

# Rosenthal / Eagar-Tsai: T_m = 4 isotherm on the surface and the side.
sl = read(os.path.join(work, "rosenthal_slices.csv"))
fig, ax = plt.subplots(2, 1, figsize=(8, 6.5))
for a, plane, label in ((ax[0], "surface", "y (m)"), (ax[1], "side", "z (m)")):
    m = sl["plane"] == plane
    xi, w = sl["xi"][m], sl["y_or_z"][m]
    xs, ws = np.unique(xi), np.unique(w)
    Ts = np.full((len(ws), len(xs)), np.nan)
    Te = np.full((len(ws), len(xs)), np.nan)
    ix = np.searchsorted(xs, xi)
    iw = np.searchsorted(ws, w)
    Ts[iw, ix] = sl["T_sim"][m]
    Te[iw, ix] = sl["T_exact"][m]
    levels = [2.0, 4.0]
    c1 = a.contour(xs, ws, Te, levels=levels, colors="k", linestyles="-")
    c2 = a.contour(xs, ws, Ts, levels=levels, colors="tab:red", linestyles="--")
    a.clabel(c1, fmt="%.0f K")
    a.set_xlabel(r"$\xi = x - vt$ (m)")
    a.set_ylabel(label)
    a.set_aspect("equal")
    a.set_title(f"{plane}: Eagar-Tsai (black) vs femp (red dashed), T = 2 and 4 K")
fig.tight_layout()
fig.savefig(os.path.join(out_dir, "rosenthal.png"), dpi=110)
print("wrote", os.path.join(out_dir, "stefan.png"), "and", os.path.join(out_dir, "rosenthal.png"))
