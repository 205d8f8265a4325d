#!/usr/bin/python3
"""femp: plots of the paper's case 3.1 (Danilovskaya thermal shock).

Usage:
  build/tests/test_solid_danilovskaya history.csv profile.csv
  /usr/bin/python3 contrib/plot_danilovskaya.py history.csv profile.csv doc/

Writes danilovskaya_history.png (sigma_x and T at probe A, the paper's
Fig. 5: closed form, all-MPM (APIC, the default, and FLIP), FEMP, all-FE) and danilovskaya_profile.png
(spatial profiles at t = 1, the paper's Fig. 6). Quantities are
nondimensional: S = sigma_x / (beta T0), theta = (T - T_ref) / T0.
The CSV files are read by contrib/femp_post.py.
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import femp_post  # noqa: E402


def read(name):
    return femp_post.read_csv(name)


def main():
    hist, prof, out = read(sys.argv[1]), read(sys.argv[2]), sys.argv[3]

    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    ax[0].plot(hist["t"], hist["S_exact"], "k-", label="closed form")
    ax[0].plot(hist["t"], hist["S_mpm_flip"], "c-", lw=0.8, label="all-MPM, FLIP")
    ax[0].plot(hist["t"], hist["S_mpm"], "b-", lw=1, label="all-MPM (APIC)")
    ax[0].plot(hist["t"], hist["S_femp"], "r--", lw=1, label="FEMP (APIC)")
    ax[0].plot(hist["t"], hist["S_fe"], "g:", lw=1, label="all-FE")
    ax[0].set_xlabel("t (nondimensional)")
    ax[0].set_ylabel("S = sigma_x / (beta T0)")
    ax[0].set_title("stress at A (x = 1.01 m)")
    ax[0].legend()
    ax[1].plot(hist["t"], hist["theta_exact"], "k-", label="closed form")
    ax[1].plot(hist["t"], hist["theta_mpm"], "b--", label="femp (one grid field in all runs)")
    ax[1].set_xlabel("t (nondimensional)")
    ax[1].set_ylabel("theta = (T - T_ref) / T0")
    ax[1].set_title("temperature at A")
    ax[1].legend()
    fig.tight_layout()
    fig.savefig(out + "/danilovskaya_history.png", dpi=120)

    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    x = prof["x"]
    ax[0].plot(x, prof["S_exact"], "k-", label="closed form")
    ax[0].plot(x, prof["S_mpm_flip"], "c-", lw=0.8, label="all-MPM, FLIP")
    ax[0].plot(x, prof["S_mpm"], "b-", lw=1, label="all-MPM (APIC)")
    ax[0].plot(x, prof["S_femp"], "r--", lw=1, label="FEMP (FE for x < 0.6)")
    ax[0].plot(x, prof["S_fe"], "g:", lw=1, label="all-FE")
    ax[0].axvline(0.6, color="grey", lw=0.5)
    ax[0].set_xlim(0, 2)
    ax[0].set_xlabel("x (m)")
    ax[0].set_ylabel("S")
    ax[0].set_title("stress at t = 1")
    ax[0].legend()
    ax[1].plot(x, prof["theta_exact"], "k-", label="closed form")
    ax[1].plot(x, prof["theta_mpm"], "b--", label="all-MPM")
    ax[1].plot(x, prof["theta_femp"], "r:", label="FEMP")
    ax[1].axvline(0.6, color="grey", lw=0.5)
    ax[1].set_xlim(0, 2)
    ax[1].set_xlabel("x (m)")
    ax[1].set_ylabel("theta")
    ax[1].set_title("temperature at t = 1")
    ax[1].legend()
    fig.tight_layout()
    fig.savefig(out + "/danilovskaya_profile.png", dpi=120)


if __name__ == "__main__":
    main()
