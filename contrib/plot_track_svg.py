#!/usr/bin/env python3
"""Pictures of a track scene (e.g. prm/case_3_2_reduced.prm) as SVG, with
Python 3 and numpy (the files are read by contrib/femp_post.py; no
matplotlib, no ParaView; h5py for HDF5 output).

    python3 contrib/plot_track_svg.py OUTPUT_DIR [FIGURE_DIR] [--x X] [--y Y] [--n N] [--prefix P]

reads from OUTPUT_DIR the field output number N (default: the last one):
the grid (VTU or HDF5), probe_line_<name>_<N>.csv and track_shape_<N>.csv,
and writes to FIGURE_DIR
(default: OUTPUT_DIR), each name preceded by P (default: none):

  section_T.svg, section_von_mises.svg   cross-section at x = X (default:
      the track-shape file's first cross-section) and longitudinal section
      at y = Y (default: its centre line) of T and of the von Mises stress,
      metal cells only (alpha >= 1/2), with the surface height z_s;
  probe_sigma_xx.svg   sigma_xx along every probe line (MPa);
  track_shape.svg      the surface height z_s along the centre line and
      across the track, the re-solidified bead's columns marked.

    python3 contrib/plot_track_svg.py --compare FIGURE.svg [--n N] DIR=label ... LINE:field ...

draws, for several runs (output directories DIR), one panel per LINE:field
(e.g. CD:T EF:sigma_xx; fields T in K, stresses in MPa) with the probe
line's profile of output N (default: each run's last; DIR@M=label takes
output M of that run, e.g. one run at several times) against x (against z
for a vertical line), and prints
the largest difference between the first two runs relative to the first
run's peak |value|, per panel and over all panels of a field (e.g. FEMP
against all-MPM, doc/cases.md).
"""
import glob
import math
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import femp_post  # noqa: E402


# ---------------------------------------------------------------- reading
def section(grid, axis, value, field):
    """{(a, b): value} of the metal cells (alpha >= 1/2) whose centre
    coordinate 'axis' (0 = x, 1 = y) is the nearest to 'value'; (a, b) the
    other horizontal coordinate and z."""
    c = grid.centres
    levels = np.unique(np.round(c[:, axis], 9))
    level = levels[np.argmin(np.abs(levels - value))]
    keep = np.isclose(c[:, axis], level, rtol=0, atol=1e-9)
    if "alpha" in grid:
        keep &= grid["alpha"] >= 0.5
    other = 1 - axis
    return level, {(float(a), float(b)): float(v) for a, b, v in
                   zip(c[keep, other], c[keep, 2], grid[field][keep])}


# ---------------------------------------------------------------- drawing
def colour(t):
    """Blue - cyan - yellow - red ramp for t in [0, 1]."""
    stops = [(0, (49, 54, 149)), (0.35, (69, 160, 200)), (0.65, (254, 224, 144)),
             (1, (165, 0, 38))]
    t = min(max(t, 0), 1)
    for (a, ca), (b, cb) in zip(stops, stops[1:]):
        if t <= b:
            f = (t - a) / (b - a)
            return "rgb(%d,%d,%d)" % tuple(int(ca[i] + f * (cb[i] - ca[i])) for i in range(3))
    return "rgb(165,0,38)"


class Svg:
    def __init__(self, w, h):
        self.w, self.h, self.items = w, h, []

    def add(self, s):
        self.items.append(s)

    def text(self, x, y, s, size=12, anchor="start", rotate=None):
        tr = ' transform="rotate(%g %g %g)"' % (rotate, x, y) if rotate else ""
        self.add('<text x="%.1f" y="%.1f" font-size="%d" font-family="sans-serif" '
                 'text-anchor="%s"%s>%s</text>' % (x, y, size, anchor, tr, s))

    def save(self, path):
        with open(path, "w") as f:
            f.write('<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" '
                    'viewBox="0 0 %d %d">\n<rect width="100%%" height="100%%" fill="white"/>\n'
                    % (self.w, self.h, self.w, self.h))
            f.write("\n".join(self.items))
            f.write("\n</svg>\n")


def nice_ticks(lo, hi, n=5):
    if hi <= lo:
        hi = lo + 1
    step = 10 ** math.floor(math.log10((hi - lo) / n))
    for m in (1, 2, 5, 10):
        if (hi - lo) / (m * step) <= n:
            step *= m
            break
    t = math.ceil(lo / step) * step
    out = []
    while t <= hi + 1e-9 * step:
        out.append(round(t, 10))
        t += step
    return out


def line_plot(path, title, xlabel, ylabel, series, hlines=()):
    """series: list of (label, xs, ys, colour)."""
    svg = Svg(640, 400)
    line_panel(svg, 0, title, xlabel, ylabel, series, hlines)
    svg.save(path)


def line_panel(svg, top, title, xlabel, ylabel, series, hlines=()):
    """One 640 x 400 line plot drawn into svg with its top at y = top."""
    L, R, T, B = 70, 150, 40, 50
    xs = [x for s in series for x in s[1]]
    ys = [y for s in series for y in s[2]] + [h for h, _ in hlines]
    x0, x1 = min(xs), max(xs)
    y0, y1 = min(ys), max(ys)
    pad = 0.05 * (y1 - y0 or 1)
    y0, y1 = y0 - pad, y1 + pad
    X = lambda x: L + (x - x0) / (x1 - x0 or 1) * (640 - L - R)
    Y = lambda y: top + 400 - B - (y - y0) / (y1 - y0) * (400 - T - B)
    svg.text(320 - R / 2 + L / 2, top + 22, title, 14, "middle")
    svg.add('<rect x="%d" y="%d" width="%d" height="%d" fill="none" stroke="black"/>'
            % (L, top + T, 640 - L - R, 400 - T - B))
    for t in nice_ticks(x0, x1):
        svg.add('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#ccc"/>'
                % (X(t), top + T, X(t), top + 400 - B))
        svg.text(X(t), top + 400 - B + 16, "%g" % t, 11, "middle")
    for t in nice_ticks(y0, y1):
        svg.add('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#ccc"/>' % (L, Y(t), 640 - R, Y(t)))
        svg.text(L - 6, Y(t) + 4, "%g" % t, 11, "end")
    for h, lab in hlines:
        svg.add('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="gray" stroke-dasharray="5,4"/>'
                % (L, Y(h), 640 - R, Y(h)))
        svg.text(640 - R - 4, Y(h) - 4, lab, 10, "end")
    for i, (label, sx, sy, c) in enumerate(series):
        dash = ' stroke-dasharray="6,4"' if i % 2 and len(series) == 2 else ""
        pts = " ".join("%.1f,%.1f" % (X(a), Y(b)) for a, b in zip(sx, sy))
        svg.add('<polyline points="%s" fill="none" stroke="%s" stroke-width="2"%s/>' % (pts, c, dash))
        svg.add('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="%s" stroke-width="2"%s/>'
                % (640 - R + 10, top + T + 10 + 18 * i, 640 - R + 30, top + T + 10 + 18 * i, c, dash))
        svg.text(640 - R + 34, top + T + 14 + 18 * i, label, 11)
    svg.text(L + (640 - L - R) / 2, top + 400 - 12, xlabel, 12, "middle")
    svg.text(18, top + T + (400 - T - B) / 2, ylabel, 12, "middle", rotate=-90)


def section_plot(path, title, panels, field, unit, scale):
    """panels: list of (label, cells {(a, b): value}, surface [(a, z)])."""
    svg = Svg(760, 150 + 260 * len(panels))
    vals = [v for _, c, _ in panels for v in c.values()]
    vmin, vmax = min(vals), max(vals)
    svg.text(380, 22, title, 14, "middle")
    y_top = 40
    for label, cells, surface in panels:
        a_vals = sorted({a for a, _ in cells})
        b_vals = sorted({b for _, b in cells})
        da = min(b - a for a, b in zip(a_vals, a_vals[1:])) if len(a_vals) > 1 else 1
        a0, a1 = a_vals[0] - da / 2, a_vals[-1] + da / 2
        b0, b1 = b_vals[0] - da / 2, b_vals[-1] + da / 2
        s = min(560 / (a1 - a0), 200 / (b1 - b0))
        X = lambda a: 80 + (a - a0) * s
        Y = lambda b: y_top + 20 + (b1 - b) * s
        svg.text(80, y_top + 12, label, 12)
        for (a, b), v in cells.items():
            svg.add('<rect x="%.2f" y="%.2f" width="%.2f" height="%.2f" fill="%s"/>'
                    % (X(a - da / 2), Y(b + da / 2), da * s + 0.3, da * s + 0.3,
                       colour((v - vmin) / (vmax - vmin or 1))))
        if surface:
            pts = " ".join("%.1f,%.1f" % (X(a), Y(z)) for a, z in surface)
            svg.add('<polyline points="%s" fill="none" stroke="black" stroke-width="1.5"/>' % pts)
        svg.add('<rect x="%.1f" y="%.1f" width="%.1f" height="%.1f" fill="none" stroke="black"/>'
                % (X(a0), Y(b1), (a1 - a0) * s, (b1 - b0) * s))
        for t in nice_ticks(a0 * 1e6, a1 * 1e6):
            svg.text(X(t * 1e-6), Y(b0) + 14, "%g" % t, 10, "middle")
        for t in nice_ticks(b0 * 1e6, b1 * 1e6, 4):
            svg.text(X(a0) - 4, Y(t * 1e-6) + 4, "%g" % t, 10, "end")
        y_top = Y(b0) + 30
    # colour bar
    for i in range(100):
        svg.add('<rect x="%.1f" y="%d" width="3.2" height="14" fill="%s"/>'
                % (80 + 3.2 * i, y_top + 10, colour(i / 99)))
    svg.text(80, y_top + 40, "%.4g" % (vmin * scale), 11)
    svg.text(400, y_top + 40, "%.4g %s" % (vmax * scale, unit), 11, "end")
    svg.text(420, y_top + 22, "%s; positions in um, metal cells only" % field, 11)
    svg.h = int(y_top + 60)
    svg.save(path)


# ---------------------------------------------------------------- compare
UNITS = {"T": ("K", 1), "sigma_xx": ("MPa", 1e-6), "sigma_yy": ("MPa", 1e-6),
         "sigma_zz": ("MPa", 1e-6), "von_mises": ("MPa", 1e-6),
         "plastic_strain": ("-", 1)}


def compare(args):
    """--compare FIGURE.svg [--n N] DIR[@M]=label ... LINE:field ...: one
    panel per LINE:field (e.g. CD:T EF:sigma_xx), the probe line's field of
    output M, else N, else the last one each run wrote, of every run
    against the line's coordinate (um); prints the largest difference
    between the first two runs relative to the peak |value| of the first."""
    path = args[0]
    n = None
    if "--n" in args:
        i = args.index("--n")
        n = int(args[i + 1])
        del args[i:i + 2]
    runs = [a.rsplit("=", 1) for a in args[1:] if "=" in a]
    panels = [a.split(":", 1) for a in args[1:] if "=" not in a]
    palette = ["#1b6ca8", "#d1495b", "#2e933c", "#edae49", "#6a4c93", "#333333"]
    svg = Svg(640, 400 * len(panels))
    overall = {}
    for k, (line, field) in enumerate(panels):
        unit, scale = UNITS.get(field, ("", 1))
        series, times = [], set()
        for i, (d, label) in enumerate(runs):
            m = n
            if "@" in d:
                d, m = d.rsplit("@", 1)
                m = int(m)
            c = femp_post.Run(d).probe_line(line, m)
            times.add("%g" % c.time)
            axis = "z" if len(set(c["x"])) == 1 and len(set(c["y"])) == 1 else \
                "y" if len(set(c["x"])) == 1 else "x"
            series.append((label, list(c[axis] * 1e6), list(c[field] * scale),
                           palette[i % len(palette)]))
        if len(series) >= 2:
            a, b = series[0][2], series[1][2]
            peak = max(abs(v) for v in a) or 1
            diff = max(abs(p - q) for p, q in zip(a, b))
            print("%s on %s: max |%s - %s| = %.4g %s = %.4f of the peak |%s| %.4g %s"
                  % (field, line, series[0][0], series[1][0], diff, unit, diff / peak,
                     series[0][0], peak, unit))
            o = overall.setdefault(field, [0, 0])
            o[0], o[1] = max(o[0], diff), max(o[1], peak)
        line_panel(svg, 400 * k, "%s on %s, t = %s s" % (field, line, " / ".join(sorted(times))),
                   "%s (um)" % axis, "%s (%s)" % (field, unit), series,
                   [(0, "")] if field != "T" else [])
    for field, (diff, peak) in overall.items():
        print("%s over all panels: max difference / largest peak = %.4f" % (field, diff / peak))
    svg.save(path)
    print("wrote", path)


# ---------------------------------------------------------------- main
def main():
    args = [a for a in sys.argv[1:]]
    if args and args[0] == "--compare":
        return compare(args[1:])
    opts = {}
    for k in ("--x", "--y", "--n", "--prefix"):
        if k in args:
            i = args.index(k)
            opts[k] = args[i + 1]
            del args[i:i + 2]
    if not args:
        sys.exit(__doc__)
    out = args[0]
    fig = args[1] if len(args) > 1 else out
    prefix = opts.get("--prefix", "")
    os.makedirs(fig, exist_ok=True)
    run = femp_post.Run(out)
    numbers = [m for m, _ in run.outputs()]
    if not numbers:
        sys.exit("no grid output (grid.pvd or grid.xdmf) in " + out)
    n = int(opts.get("--n", numbers[-1]))

    shape_file = os.path.join(out, "track_shape_%05d.csv" % n)
    shape = run.track_shape(n) if os.path.exists(shape_file) else None
    z_top = None
    if shape:
        for h in shape.header:
            m = re.search(r"substrate top z = ([-0-9.e+]+)", h)
            if m:
                z_top = float(m.group(1))
    centre_y = cross_x = None
    if shape:
        cy = shape["y"][shape["section"] == "centre"]
        cx = shape["x"][shape["section"] == "cross_1"]
        centre_y = float(cy[0]) if len(cy) else None
        cross_x = float(cx[0]) if len(cx) else None
    x_cut = float(opts.get("--x", cross_x if cross_x is not None else 0))
    y_cut = float(opts.get("--y", centre_y if centre_y is not None else 0))

    grid = run.grid(n)
    time = "%g" % grid.time

    def surface(section, coord):
        if not shape:
            return []
        keep = shape["section"] == section
        return [(float(a), float(z)) for a, z in
                zip(shape[coord][keep], shape["surface_z"][keep])]

    for field, unit, scale, name in (("T", "K", 1, "section_T.svg"),
                                     ("von_mises", "MPa", 1e-6, "section_von_mises.svg")):
        if field not in grid:
            continue
        xc, cross = section(grid, 0, x_cut, field)
        yc, longi = section(grid, 1, y_cut, field)
        section_plot(os.path.join(fig, prefix + name), "%s at t = %s s" % (field, time),
                     [("cross-section x = %.0f um (y, z)" % (xc * 1e6), cross, surface("cross_1", "y")),
                      ("longitudinal section y = %.0f um (x, z)" % (yc * 1e6), longi, surface("centre", "x"))],
                     field, unit, scale)

    palette = ["#1b6ca8", "#d1495b", "#2e933c", "#edae49", "#6a4c93", "#333333"]
    series = []
    for i, label in enumerate(run.probe_line_names()):
        if n not in run.probe_line_numbers(label):
            continue
        d = run.probe_line(label, n)
        if "sigma_xx" not in d:
            continue
        series.append((label, list(d["s"] * 1e6), list(d["sigma_xx"] * 1e-6),
                       palette[i % len(palette)]))
    if series:
        line_plot(os.path.join(fig, prefix + "probe_sigma_xx.svg"),
                  "sigma_xx along the probe lines, t = %s s" % time,
                  "distance along the line (um)", "sigma_xx (MPa)", series, [(0, "")])
    if shape:
        c = [(a * 1e6, (z - z_top) * 1e6) for a, z in surface("centre", "x")]
        x = [(a * 1e6, (z - z_top) * 1e6) for a, z in surface("cross_1", "y")]
        line_plot(os.path.join(fig, prefix + "track_shape.svg"),
                  "surface height above the substrate top, t = %s s" % time,
                  "x (centre line) or y (cross-section) (um)", "z_s - substrate top (um)",
                  [("centre line, along x", [a for a, _ in c], [b for _, b in c], palette[0]),
                   ("cross-section x = %.0f um, along y" % (cross_x * 1e6),
                    [a for a, _ in x], [b for _, b in x], palette[1])],
                  [(0, "substrate top")])
    print("wrote the figures of output %d (t = %s s) to %s" % (n, time, fig))


if __name__ == "__main__":
    main()
