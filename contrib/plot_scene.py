#!/usr/bin/env python3
"""Plot the CSV output of a femp scene: melt-pool size and peak temperature
over time (melt_pool.csv), and the temperature along each probe line at its
last output (probe_line_<name>_<n>.csv).

Usage: /usr/bin/python3 contrib/plot_scene.py OUTPUT_DIR [PNG]
Needs Debian's python3-matplotlib and python3-numpy.
"""
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import femp_post  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 else "output"
png = sys.argv[2] if len(sys.argv) > 2 else os.path.join(out, "scene.png")
run = femp_post.Run(out)

pool = run.melt_pool()
fig, ax = plt.subplots(1, 2, figsize=(11, 4))
t = pool["time"] * 1e3
for key, label in (("length", "length"), ("width", "width"), ("depth", "depth below substrate top")):
    ax[0].plot(t, pool[key] * 1e6, label=label)
ax[0].set_xlabel("t (ms)")
ax[0].set_ylabel("melt pool (um)")
ax0b = ax[0].twinx()
ax0b.plot(t, pool["T_max"], "k:", label="T_max")
ax0b.set_ylabel("peak temperature (K)")
ax[0].legend(loc="upper left")
ax[0].set_title("melt pool")
for name in run.probe_line_names():
    d = run.probe_line(name)
    ax[1].plot(d["s"] * 1e6, d["T"],
               label="%s (output %d, t = %.3g s)" % (name, d.n, d.time))
ax[1].set_xlabel("distance along line (um)")
ax[1].set_ylabel("T (K)")
ax[1].legend()
ax[1].set_title("probe lines, last output")
fig.tight_layout()
fig.savefig(png, dpi=100)
print("wrote", png)
