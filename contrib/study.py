#!/usr/bin/env python3
"""Speed against accuracy studies of femp (doc/speed_accuracy.md).

One command per study; each runs a program over a parameter sweep, one run
directory per point of the sweep, and skips runs whose result.json exists
(resumable: rerun the same command after an interruption). It collects the
CPU seconds of every run (user + system of the run and its children, from
the operating system) and an error against a named reference, writes a CSV
and an error-versus-cost plot (log-log, Pareto front marked) as SVG, drawn
with the standard library (matplotlib is not needed). The runs' files are
read by contrib/femp_post.py (numpy).

  contrib/study.py stefan       [--build build] [--out study] [--img doc/img]
  contrib/study.py mass_scaling [--build build] [--out study] [--img doc/img]
                                [--np 1]
  contrib/study.py danilovskaya | droplet | physics | track |
                   track_surface | rosenthal |
                   dam_break | static_droplet | solid_step  [same options]

stefan: the two-phase Stefan problem (tests/stefan_two_phase.cc, closed
  form of Neumann) over cell size h x step fraction of the stable step;
  error: relative error of the melt front at t = 1 against the closed form
  (as the test prints it, 2 digits); the largest error of the temperature
  profile is written as well.
mass_scaling: the reduced coupled single track (prm/single_track_coupled.prm
  on a shorter box and time) over Solid/Mass scaling factor 1 ... 1e4 and
  the adaptive mass scaling (Solid/Mass scaling = adaptive, four targets);
  error: RMS of the difference of sigma_xx at solid probe points in the
  melt-pool region at the end time against the run with factor 1, relative
  to the RMS of that run's values. Also written: the stress work and
  the booked transfer dissipation at the end, the largest
  kinetic-to-internal ratio (doc/speed_accuracy.md explains them).
danilovskaya: case 3.1 (tests/solid_danilovskaya.cc --study) over all-MPM /
  FEMP / all-FE x cell size x points per cell x APIC/FLIP x bulk viscosity;
  error: mean |sigma - exact| / (beta T0) at x = 1 m over the 2 s.
droplet: the oscillating 2D droplet (tests/oscillating_droplet.cc) over
  R/h x capillary step fraction x FLIP fraction; error: |period error|.
physics: the default scene (prm/case_3_2_reduced.prm) thermal only,
  thermo-fluid and fully coupled: cost, pool size, peak temperature, energy
  lost to evaporation (no error: a table).
track: the default scene with heat and flow (no solid) to 50 us over cell
  size 8, 4 um x temperature step (fixed 200, 100, 100.1, 50, 25 ns, and
  automatic), 2 um at 50 and 50.05 ns; error: fusion-zone depth (solidus,
  in the substrate; the width's error is written too, but it scatters by up
  to 15 % under a 0.1 % change of the step) against the finest run (2 um,
  50 ns).
track_surface: that track with femp's default free surface and with the
  height-function curvature, two smoothing passes and point shifting 2, at
  8, 4 um (100, 100.1 ns) and 2 um (50, 50.05 ns); error: fusion-zone
  depth against the 2 um, 50 ns run of the same setting.
rosenthal: the moving Gaussian source on a half space (tests/rosenthal.cc)
  over cell size x temperature step fraction of the stable step; error: the
  largest relative error of pool length, width and depth at t = 1 against
  the Eagar-Tsai (Rosenthal) closed form; also the length error against
  the pool at t = 1 of the source switched on at t = 0.
dam_break: the dam break (tests/dam_break.cc) over cells per column width
  x FLIP fraction x Courant number; error: relative error of the front
  speed after the release phase (T >= 1.19) against Martin & Moyce; the
  largest relative column-height error is written as well.
static_droplet: the 2D static drop (tests/static_droplet.cc, solver
  defaults) over R/h x FLIP fraction x capillary step fraction, to
  2.5 sqrt(rho R^3/sigma); error: relative error of the Laplace pressure
  jump; the spurious-current capillary number is written as well.
solid_step: the reduced case 3.2 with its cooling (prm/case_3_2_cooling.prm,
  melt flow off, so that every run sees the same temperatures) over
  Solid/Mass scaling factor x Solid/Safety factor; error: the largest
  difference of sigma_xx on the probe lines CD, EF and cross over the
  field outputs from 100 us on, relative to the line's peak |sigma_xx|,
  against the run with s = 100 and safety factor 0.5 (the paper's
  factor and femp's default step); eta = sqrt(s) / C is written too.
"""
import argparse
import csv
import json
import math
import os
import re
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "contrib"))
import femp_post  # noqa: E402


# ---------------------------------------------------------------- runs
def run_timed(cmd, cwd, log):
    """Run cmd in cwd, stdout+stderr to log; return (exit code, CPU s, wall s)."""
    t0 = time.time()
    with open(log, "w") as out:
        p = subprocess.Popen(cmd, cwd=cwd, stdout=out, stderr=subprocess.STDOUT)
        _, status, ru = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    return p.returncode, ru.ru_utime + ru.ru_stime, time.time() - t0


def cached(run_dir, make):
    """result.json of run_dir, or make(run_dir) stored there."""
    f = os.path.join(run_dir, "result.json")
    if os.path.exists(f):
        with open(f) as fh:
            return json.load(fh)
    os.makedirs(run_dir, exist_ok=True)
    r = make(run_dir)
    with open(f, "w") as fh:
        json.dump(r, fh, indent=1)
    return r


def set_parameters(text, values):
    """Replace 'set NAME = ...' lines of a .prm text; values maps
    'Sub/Section/Name' to the new value. A missing entry is inserted at the
    end of its subsection (which must exist, or be the top level)."""
    lines, path, done = text.split("\n"), [], set()
    out = []
    for line in lines:
        s = line.split("#")[0].strip()
        m = re.match(r"subsection\s+(.*)$", s)
        if m:
            path.append(m.group(1).strip())
        elif s == "end":
            here = "/".join(path)
            for k, v in values.items():
                if k not in done and k.rsplit("/", 1)[0] == here:
                    out.append("  set %s = %s" % (k.rsplit("/", 1)[1], v))
                    done.add(k)
            path.pop()
        else:
            m = re.match(r"set\s+(.*?)\s*=", s)
            if m:
                key = "/".join(path + [m.group(1)])
                if key in values:
                    indent = line[: len(line) - len(line.lstrip())]
                    line = "%sset %s = %s" % (indent, m.group(1), values[key])
                    done.add(key)
        out.append(line)
    for k, v in values.items():
        if k not in done:
            if "/" in k:
                raise SystemExit("study.py: subsection of %s not in the scene" % k)
            out.append("set %s = %s" % (k, v))
    return "\n".join(out)


def column_max(table, key):
    """The largest value of a column of a femp_post Table."""
    return max(table[key].tolist())


def stefan_profile_error(d):
    """The largest |T_sim - T_exact| of stefan_profile.csv in d."""
    prof = femp_post.read_csv(os.path.join(d, "stefan_profile.csv"))
    return max(abs(a - b) for a, b in zip(prof["T_sim"].tolist(),
                                          prof["T_exact"].tolist()))


def solid_run_figures(out):
    """The last probe row and the energy accounts of a solid run's output
    directory (Solid/Probe file, Solid/Energy file), as a dict."""
    run = femp_post.Run(out)
    probes = run.solid_probes()
    r = {"sxx": [float(v[-1]) for k, v in probes.items()
                 if k.startswith("sigma_xx")],
         "probe_time": float(next(iter(probes.values()))[-1])}
    e = run.solid_energy()
    late = len(e) // 10
    r["stress_work"] = float(e["internal_work"][-1])
    r["transfer"] = float(e["transfer_dissipation"][-1])
    r["remap"] = float(e["remap_work"][-1])
    r["max_k_over_i"] = max(e["kinetic_to_internal"][late:].tolist())
    r["solid_steps"] = int(e["step"][-1])
    r["balance"] = float(e["balance"][-1])
    if "mass_scaling" in e:
        s = e["mass_scaling"].tolist()
        r["s_min"], r["s_max"] = min(s), max(s)
        r["s_end"] = s[-1]
        r["k_jump"] = float(e["mass_scaling_kinetic_jump"][-1])
        r["max_k_over_el"] = max(e["kinetic_to_elastic"][late:].tolist())
    return r


# ---------------------------------------------------------------- output
def pareto(points):
    """Indices of points not dominated in (cost, error), both smaller better."""
    idx = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in idx:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def svg_loglog(path, rows, xkey, ykey, label, title, xlabel, ylabel):
    """Error-cost scatter on log axes, Pareto front joined, points labelled."""
    pts = [(r[xkey], r[ykey], r[label]) for r in rows
           if r[xkey] > 0 and r[ykey] is not None and r[ykey] > 0]
    if not pts:
        return
    W, H, L, R, T, B = 640, 460, 80, 20, 40, 60
    lx = [math.log10(p[0]) for p in pts]
    ly = [math.log10(p[1]) for p in pts]
    x0, x1 = math.floor(min(lx)), math.ceil(max(lx))
    y0, y1 = math.floor(min(ly)), math.ceil(max(ly))
    x1, y1 = max(x1, x0 + 1), max(y1, y0 + 1)
    X = lambda v: L + (math.log10(v) - x0) / (x1 - x0) * (W - L - R)
    Y = lambda v: H - B - (math.log10(v) - y0) / (y1 - y0) * (H - T - B)
    o = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" '
         'font-family="sans-serif" font-size="11">' % (W, H),
         '<rect width="100%" height="100%" fill="white"/>',
         '<text x="%d" y="20" font-size="14">%s</text>' % (L, title)]
    for e in range(x0, x1 + 1):
        x = L + (e - x0) / (x1 - x0) * (W - L - R)
        o.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#ddd"/>'
                 % (x, T, x, H - B))
        o.append('<text x="%.1f" y="%d" text-anchor="middle">1e%d</text>'
                 % (x, H - B + 16, e))
    for e in range(y0, y1 + 1):
        y = H - B - (e - y0) / (y1 - y0) * (H - T - B)
        o.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#ddd"/>'
                 % (L, y, W - R, y))
        o.append('<text x="%d" y="%.1f" text-anchor="end">1e%d</text>'
                 % (L - 6, y + 4, e))
    o.append('<rect x="%d" y="%d" width="%d" height="%d" fill="none" '
             'stroke="black"/>' % (L, T, W - L - R, H - T - B))
    o.append('<text x="%d" y="%d" text-anchor="middle">%s</text>'
             % ((L + W - R) // 2, H - 20, xlabel))
    o.append('<text x="18" y="%d" text-anchor="middle" transform="rotate(-90 '
             '18 %d)">%s</text>' % ((T + H - B) // 2, (T + H - B) // 2, ylabel))
    front = pareto([(p[0], p[1]) for p in pts])
    o.append('<polyline fill="none" stroke="red" stroke-width="1.5" points="%s"/>'
             % " ".join("%.1f,%.1f" % (X(pts[i][0]), Y(pts[i][1])) for i in front))
    for i, p in enumerate(pts):
        on = i in front
        o.append('<circle cx="%.1f" cy="%.1f" r="%d" fill="%s"/>'
                 % (X(p[0]), Y(p[1]), 4 if on else 3, "red" if on else "#36c"))
        if on or len(pts) <= 30:  # crowded charts: only the front named
            o.append('<text x="%.1f" y="%.1f" font-size="9">%s</text>'
                     % (X(p[0]) + 5, Y(p[1]) - 4, p[2]))
    o.append('<text x="%d" y="%d" fill="red">red: Pareto front (no run both '
             'cheaper and more accurate)</text>' % (L + 8, T + 14))
    o.append("</svg>")
    with open(path, "w") as fh:
        fh.write("\n".join(o) + "\n")


def write_outputs(name, rows, fields, args, title, xlabel, ylabel):
    os.makedirs(args.out, exist_ok=True)
    f = os.path.join(args.out, name + ".csv")
    with open(f, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow(r)
    front = pareto([(r["cpu_s"], r["error"] if r["error"] else math.inf)
                    for r in rows])
    for i, r in enumerate(rows):
        r["pareto"] = i in front
    with open(f, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields + ["pareto"],
                           extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow(r)
    os.makedirs(args.img, exist_ok=True)
    svg = os.path.join(args.img, "study_%s.svg" % name)
    svg_loglog(svg, rows, "cpu_s", "error", "label", title, xlabel, ylabel)
    print("wrote", f, "and", svg)
    for r in rows:
        print("  ".join("%s=%s" % (k, r.get(k, "")) for k in fields + ["pareto"]))
    missing = [r["label"] for r in rows
               if r.get("error") is None and not r.get("reference")]
    if missing:
        raise SystemExit("study.py: no result from the runs %s (see log.txt "
                         "in their folders under %s)" % (", ".join(missing),
                                                         args.out))


# ---------------------------------------------------------------- studies
def study_stefan(args):
    exe = os.path.join(args.build, "tests", "test_stefan_two_phase")
    if not os.path.exists(exe):
        raise SystemExit("study.py: build %s first (cmake --build %s --target "
                         "test_stefan_two_phase)" % (exe, args.build))
    exe = os.path.abspath(exe)
    rows = []
    for h in (0.04, 0.02, 0.01, 0.005):
        for c in (0.1, 0.25, 0.5, 1.0):
            def make(d, h=h, c=c):
                rc, cpu, wall = run_timed([exe, str(h), str(c)], d,
                                          os.path.join(d, "log.txt"))
                text = open(os.path.join(d, "log.txt")).read()
                m = re.search(r"front t=1 \([^)]*\): relative error = ([-0-9.e+]+)",
                              text)
                return {"rc": rc, "cpu_s": cpu, "wall_s": wall,
                        "error": float(m.group(1)) if m else None}
            d = os.path.join(args.out, "stefan", "h%g_c%g" % (h, c))
            r = cached(d, make)
            # Also the largest temperature error of the final profile against
            # the Neumann solution (K per K of the driving difference; it
            # has a floor of ~0.055 from the domain's far face, held at
            # T_m - 1 K at x = 3 where the half-space solution is 0.06 K
            # warmer).
            try:
                r["profile_error"] = stefan_profile_error(d)
            except (OSError, ValueError):
                r["profile_error"] = None
            r.update(h=h, step_fraction=c, label="h=%g,C=%g" % (h, c))
            rows.append(r)
    write_outputs("stefan", rows,
                  ["h", "step_fraction", "cpu_s", "wall_s", "error",
                   "profile_error", "rc"], args,
                  "Stefan problem: front error at t = 1 vs CPU time",
                  "CPU seconds", "relative front error")


def study_danilovskaya(args):
    exe = os.path.join(args.build, "tests", "test_solid_danilovskaya")
    if not os.path.exists(exe):
        raise SystemExit("study.py: build %s first (cmake --build %s --target "
                         "test_solid_danilovskaya)" % (exe, args.build))
    exe = os.path.abspath(exe)
    rows = []
    keys = ("points", "elements", "steps", "max_error_away", "max_error_far",
            "mean_error", "rms_error", "front_error", "balance")
    for method in ("mpm", "femp", "fe"):
        for h in (0.04, 0.02, 0.01, 0.005):
            for ppc in ((1, 2) if method != "fe" else (1,)):
                for tr in (("apic", "flip") if method != "fe" else ("apic",)):
                    for bv in (0, 0.1, 0.3):
                        def make(d, a=(method, h, ppc, tr, bv)):
                            cmd = [exe, "--study"] + [str(v) for v in a]
                            rc, cpu, wall = run_timed(
                                cmd, d, os.path.join(d, "log.txt"))
                            text = open(os.path.join(d, "log.txt")).read()
                            r = {"rc": rc, "cpu_s": cpu, "wall_s": wall}
                            for k in keys:
                                m = re.search(r"\b%s ([-0-9.e+naif]+)" % k, text)
                                r[k] = float(m.group(1)) if m else None
                            return r
                        d = os.path.join(args.out, "danilovskaya",
                                         "%s_h%g_p%d_%s_b%g" % (method, h, ppc,
                                                                 tr, bv))
                        r = cached(d, make)
                        r.update(method=method, h=h, points_per_cell=ppc,
                                 transfer=tr, bulk_viscosity=bv,
                                 error=r["mean_error"],
                                 label="%s %g%s%s b%g" % (
                                     method, h,
                                     " p%d" % ppc if ppc > 1 else "",
                                     " F" if tr == "flip" else "", bv))
                        rows.append(r)
    write_outputs("danilovskaya", rows,
                  ["method", "h", "points_per_cell", "transfer",
                   "bulk_viscosity", "cpu_s", "wall_s", "error", "rms_error",
                   "max_error_away", "max_error_far", "front_error", "balance", "points", "elements", "steps",
                   "rc"], args,
                  "Danilovskaya (case 3.1): mean |S - exact| at x = 1 m "
                  "over 2 s vs CPU time", "CPU seconds",
                  "mean |sigma - exact| / (beta T0)")


def study_physics(args):
    """The default scene (reduced case 3.2, to its end time of 150 us, its
    fixed temperature step of 100 ns) with the physics switched on one by
    one: heat only, heat + melt flow, heat + flow + solid stress; what each
    costs (CPU s) and what it changes: the run's largest pool length,
    width, depth, fusion-zone depth and width (solidus, in the substrate),
    peak temperature, energy lost to evaporation. About 35 CPU seconds on
    one rank in all."""
    exe = os.path.abspath(os.path.join(args.build, "femp"))
    scene = os.path.join(ROOT, "prm", "case_3_2_reduced.prm")
    rows = []
    for name, flow, solid in (("thermal", "false", "false"),
                              ("thermo-fluid", "true", "false"),
                              ("coupled", "true", "true")):
        def make(d, flow=flow, solid=solid):
            sets = {"Physics/Melt flow": flow, "Physics/Solid stress": solid,
                    "Output/Directory": d, "Output/Output interval": "0",
                    "Output/Write material points": "never"}
            cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np",
                   str(args.np), exe] if args.np > 1 else [exe]
            for k, v in sets.items():
                cmd += ["--set", "%s=%s" % (k, v)]
            rc, cpu, wall = run_timed(cmd + [scene], d,
                                      os.path.join(d, "log.txt"))
            text = open(os.path.join(d, "log.txt")).read()
            r = {"rc": rc, "cpu_s": cpu, "wall_s": wall}
            r.update(run_log_figures(text))
            m = re.search(r"Solid: ([0-9]+) steps of", text)
            r["solid_steps"] = int(m.group(1)) if m else None
            pool = femp_post.Run(d).melt_pool()
            for k in ("length", "width", "depth", "T_max",
                      "depth_solidus_substrate", "width_solidus_substrate"):
                r["max_" + k] = column_max(pool, k)
            return r
        d = os.path.join(args.out, "physics", name)
        r = cached(d, make)
        r.update(physics=name, label=name, error=None)
        rows.append(r)
    fields = ["physics", "cpu_s", "wall_s", "max_length", "max_width",
              "max_depth", "max_depth_solidus_substrate",
              "max_width_solidus_substrate", "max_T_max", "laser_J",
              "evaporation_J", "losses_J", "steps", "fluid_steps",
              "solid_steps", "rc"]
    os.makedirs(args.out, exist_ok=True)
    f = os.path.join(args.out, "physics.csv")
    with open(f, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow(r)
    print("wrote", f)
    for r in rows:
        print("  ".join("%s=%s" % (k, r.get(k, "")) for k in fields))
    failed = [r["physics"] for r in rows if r["rc"] != 0]
    if failed:
        raise SystemExit("study.py: the runs %s failed (log.txt under %s)"
                         % (", ".join(failed), args.out))


def study_droplet(args):
    """Oscillating 2D droplet (tests/oscillating_droplet.cc, Lamb's mode-2
    period with the viscous shift): radius in cells x capillary step
    fraction x FLIP fraction; error: |period error| of the first full
    period."""
    exe = os.path.join(args.build, "tests", "test_oscillating_droplet")
    if not os.path.exists(exe):
        raise SystemExit("study.py: build %s first (cmake --build %s --target "
                         "test_oscillating_droplet)" % (exe, args.build))
    exe = os.path.abspath(exe)
    rows = []
    for r_h in (10, 15, 20, 30):
        for frac in (0.25, 0.5, 1.0):
            for flip in (0.9, 0.95, 0.99):
                def make(d, a=(frac, r_h, flip)):
                    cmd = [exe, str(a[0]), str(a[1]), "", "0.5", "0.1",
                           str(a[2])]
                    rc, cpu, wall = run_timed(cmd, d,
                                              os.path.join(d, "log.txt"))
                    text = open(os.path.join(d, "log.txt")).read()
                    r = {"rc": rc, "cpu_s": cpu, "wall_s": wall}
                    m = re.search(r"\|period error\|[^=]*= ([-0-9.e+]+)", text)
                    r["period_error"] = float(m.group(1)) if m else None
                    m = re.search(r"\nsteps = ([0-9]+)", text)
                    r["steps"] = int(m.group(1)) if m else None
                    m = re.search(r"max point speed / \(omega eps R\) = "
                                  r"([-0-9.e+]+)", text)
                    r["max_speed"] = float(m.group(1)) if m else None
                    return r
                d = os.path.join(args.out, "droplet",
                                 "R%g_c%g_f%g" % (r_h, frac, flip))
                r = cached(d, make)
                r.update(R_over_h=r_h, step_fraction=frac, flip=flip,
                         error=r["period_error"],
                         label="R%gh c%g f%g" % (r_h, frac, flip))
                rows.append(r)
    write_outputs("droplet", rows,
                  ["R_over_h", "step_fraction", "flip", "cpu_s", "wall_s",
                   "error", "steps", "max_speed", "rc"], args,
                  "Oscillating droplet: period error vs CPU time",
                  "CPU seconds", "|period error| / T")


def run_log_figures(text):
    """Figures of a femp run's final report (log.txt), by
    femp_post.read_printed: temperature steps, fluid steps, sub-steps per
    temperature step, energies."""
    lines = text.split("\n")

    def printed(pattern):
        return femp_post.read_printed(lines, pattern)

    r = {}
    m = printed(r"step +([0-9]+) +dt =")
    r["steps"] = int(m["1"][-1]) if len(m) else None
    m = printed(r"Melt flow: ([0-9]+) fluid steps")
    r["fluid_steps"] = int(m["1"][0]) if len(m) else None
    m = printed(r"sub-steps per temperature step ([0-9]+) to ([0-9]+)")
    r["substeps"] = ("%d-%d" % (m["1"][0], m["2"][0])) if len(m) else ""
    m = printed(r"Energy \(J\): laser ([-0-9.e+]+), surface losses "
                r"([-0-9.e+]+) \(evaporation ([-0-9.e+]+)")
    if len(m):
        r.update(laser_J=float(m["1"][0]), losses_J=float(m["2"][0]),
                 evaporation_J=float(m["3"][0]))
    return r


def fusion_errors(rows, ref):
    """Relative errors of the largest fusion-zone depth ('depth_error', also
    the plotted 'error') and width ('width_error') of the track runs @p rows
    against the run @p ref, which is marked as the reference."""
    for r in rows:
        try:
            r["depth_error"] = abs(r["max_depth_solidus_substrate"] /
                                   ref["max_depth_solidus_substrate"] - 1)
            r["width_error"] = abs(r["max_width_solidus_substrate"] /
                                   ref["max_width_solidus_substrate"] - 1)
            r["error"] = r["depth_error"]
        except (KeyError, ZeroDivisionError, TypeError):
            r["error"] = None
        if r is ref:
            r["error"], r["reference"] = None, True


def track_run(args, exe, scene, d, h, dt, extra):
    """One run of the track studies: the default scene with heat and flow
    (no solid) to 50 us at cell size h, point spacing h/2 and the fixed
    temperature step dt (0: automatic), plus the settings @p extra; returns
    the cost, the log's figures and the maxima of melt_pool.csv."""
    sets = {"Physics/Solid stress": "false",
            "Time stepping/End time": "5e-5",
            "Time stepping/Time step": str(dt),
            "Background grid/Cell size": str(h),
            "Material points/Point spacing": str(h / 2),
            "Output/Directory": d, "Output/Output interval": "0",
            "Output/Write material points": "never"}
    sets.update(extra)
    cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe",
           "-np", str(args.np), exe] if args.np > 1 else [exe]
    for k, v in sets.items():
        cmd += ["--set", "%s=%s" % (k, v)]
    rc, cpu, wall = run_timed(cmd + [scene], d, os.path.join(d, "log.txt"))
    r = {"rc": rc, "cpu_s": cpu, "wall_s": wall}
    r.update(run_log_figures(open(os.path.join(d, "log.txt")).read()))
    try:
        pool = femp_post.Run(d).melt_pool()
        for k in ("depth_solidus_substrate", "width_solidus_substrate",
                  "T_max", "depth", "width", "length"):
            r["max_" + k] = column_max(pool, k)
    except (OSError, ValueError, KeyError) as ex:
        r["read_error"] = str(ex)
    return r


def study_track_surface(args):
    """The track of study 'track' (heat and flow, no solid, 50 us) with
    femp's default free surface (alpha-gradient curvature, no smoothing, no
    point shifting) and with the setting that carries finely resolved
    surfaces (Melt flow/Curvature = height function, Curvature smoothing =
    2, Point shifting = 2; doc/stability.md "A capillary wave on a flat
    layer"), each at 8 and 4 um (100 ns and 100.1 ns) and 2 um (50 and
    50.05 ns, the reference of its setting). Error: the largest fusion-zone
    depth against the 2 um, 50 ns run of the same setting; the 0.1 %
    perturbed steps show the scatter. About 20 CPU minutes, 15 of them at
    2 um."""
    exe = os.path.abspath(os.path.join(args.build, "femp"))
    scene = os.path.join(ROOT, "prm", "case_3_2_reduced.prm")
    fine = {"Melt flow/Curvature": "height function",
            "Melt flow/Curvature smoothing": "2",
            "Melt flow/Point shifting": "2"}
    rows = []
    for name, extra in (("defaults", {}), ("fine surface", fine)):
        mine = []
        for h, dt in ((8e-6, 1e-7), (8e-6, 1.001e-7), (4e-6, 1e-7),
                      (4e-6, 1.001e-7), (2e-6, 5.005e-8), (2e-6, 5e-8)):
            def make(d, h=h, dt=dt, extra=extra):
                return track_run(args, exe, scene, d, h, dt, extra)
            d = os.path.join(args.out, "track_surface",
                             "%s_h%g_dt%g" % (name.replace(" ", "_"), h, dt))
            r = cached(d, make)
            r.update(setting=name, h=h, dt=dt,
                     label="%s %gum %gns" % (name, h * 1e6, dt * 1e9))
            mine.append(r)
        fusion_errors(mine, mine[-1])
        rows += mine
    write_outputs("track_surface", rows,
                  ["setting", "h", "dt", "cpu_s", "wall_s", "error",
                   "width_error", "max_depth_solidus_substrate",
                   "max_width_solidus_substrate", "max_T_max", "max_depth",
                   "max_width", "max_length", "steps", "fluid_steps",
                   "substeps", "evaporation_J", "rc"], args,
                  "Track to 50 us, default and fine free surface: depth "
                  "vs own 2 um run",
                  "CPU seconds", "relative error of the fusion-zone depth")


def study_track(args):
    """The default scene's track with heat and melt flow (no solid), to
    50 us (the laser's whole path): cell size 8, 4 um (point spacing h/2)
    x temperature step 'Time stepping/Time step' = 200, 100, 100.1, 50,
    25 ns and 0 (automatic: 0.5 x the stable limit of diffusion and
    convection, variable), and 2 um at 50 ns (the reference) and 50.05 ns.
    The scene's step is fixed (prescribed, refused above the stable limit);
    the flow sub-cycles inside it with its own limits, in equal pieces no
    longer than the temperature step, so a shorter temperature step
    shortens the flow step as well wherever the flow's own limit is longer.
    Error: the largest fusion-zone depth (solidus, in the substrate, the
    run's maximum in melt_pool.csv) against the finest run (2 um, 50 ns);
    the error of the largest fusion-zone width is written as well. The
    steps of 100.1 and 50.05 ns, 0.1 % off 100 and 50 ns, measure the
    scatter of these figures under a perturbation far below any
    discretization error (the melt flow over the powder is chaotic): the
    width moves by 4-15 % under it, the depth by 0.03-1.5 % (8 and 4 um),
    so only the depth can rank the settings and it is the plotted error.
    About 10 CPU minutes on one rank, 7 of them for the two 2 um runs."""
    exe = os.path.abspath(os.path.join(args.build, "femp"))
    scene = os.path.join(ROOT, "prm", "case_3_2_reduced.prm")
    rows = []
    sweep = [(h, dt) for h in (8e-6, 4e-6)
             for dt in (0, 2e-7, 1e-7, 1.001e-7, 5e-8, 2.5e-8)]
    # The finest cells: the reference (50 ns; the flow takes 2-3 sub-steps
    # of ~20 ns in it) and its 0.1 % perturbation.
    sweep += [(2e-6, 5.005e-8), (2e-6, 5e-8)]
    for h, dt in sweep:
        def make(d, h=h, dt=dt):
            return track_run(args, exe, scene, d, h, dt, {})
        d = os.path.join(args.out, "track", "h%g_dt%g" % (h, dt))
        r = cached(d, make)
        r.update(h=h, dt=dt if dt > 0 else "auto",
                 label="%gum %s" % (h * 1e6, "%gns" % (dt * 1e9) if dt > 0
                                    else "auto"))
        rows.append(r)
    fusion_errors(rows, rows[-1])
    write_outputs("track", rows,
                  ["h", "dt", "cpu_s", "wall_s", "error", "depth_error",
                   "width_error", "max_depth_solidus_substrate",
                   "max_width_solidus_substrate", "max_T_max", "max_depth",
                   "max_width", "max_length", "steps", "fluid_steps",
                   "substeps", "evaporation_J", "rc"], args,
                  "Reduced case 3.2, heat + flow to 50 us: fusion depth vs "
                  "the 2 um / 50 ns run", "CPU seconds",
                  "relative error of the fusion-zone depth")


def run_test_sweep(args, name, target, points):
    """Run build/tests/TARGET once per (folder, argv, extra columns) of
    points, each in its own folder under args.out/name; return the rows
    with rc, cpu_s, wall_s, the log text under 'log' (not stored)."""
    exe = os.path.join(args.build, "tests", target)
    if not os.path.exists(exe):
        raise SystemExit("study.py: build %s first (cmake --build %s --target "
                         "%s)" % (exe, args.build, target))
    exe = os.path.abspath(exe)
    rows = []
    for folder, argv, extra in points:
        def make(d, argv=argv):
            rc, cpu, wall = run_timed([exe] + argv, d,
                                      os.path.join(d, "log.txt"))
            return {"rc": rc, "cpu_s": cpu, "wall_s": wall}
        d = os.path.join(args.out, name, folder)
        r = cached(d, make)
        with open(os.path.join(d, "log.txt")) as fh:
            r["log"] = fh.read()
        r.update(extra)
        rows.append(r)
    return rows


def number(pattern, text):
    """The float of the first group of pattern in text, or None."""
    m = re.search(pattern, text)
    return float(m.group(1)) if m else None


NUM = r"([-+]?(?:[0-9][0-9.]*(?:e[-+]?[0-9]+)?|nan|inf))"


def study_rosenthal(args):
    """Moving Gaussian source (tests/rosenthal.cc): cell size x step
    fraction C of the stable temperature step; error: the largest relative
    error of the pool's length, width and depth at t = 1 against the
    closed form (unrounded, from the test's log)."""
    points = []
    for n in (10, 20, 30, 40, 50, 60):  # cells per 2 (h = 2/n)
        for c in ((0.25, 0.5, 1.0) if n < 60 else (0.5, 1.0)):
            h = 2.0 / n
            points.append(("h%.4g_c%g" % (h, c), [repr(h), str(c)],
                           {"h": round(h, 5), "step_fraction": c,
                            "label": "h=%.3g,C=%g" % (h, c)}))
    rows = run_test_sweep(args, "rosenthal", "test_rosenthal", points)
    for r in rows:
        text = r.pop("log")
        for k in ("length", "width", "depth"):
            r[k + "_error"] = number(r"unrounded relative errors:.*\b%s %s"
                                     % (k, NUM), text)
        r["steps"] = number(r"\nsteps ([0-9]+)", text)
        r["length_error_t1"] = number(r"switched on at t = 0 .*relative "
                                      r"error " + NUM, text)
        e = [r[k + "_error"] for k in ("length", "width", "depth")]
        r["error"] = max(e) if None not in e else None
    write_outputs("rosenthal", rows,
                  ["h", "step_fraction", "cpu_s", "wall_s", "error",
                   "length_error", "width_error", "depth_error",
                   "length_error_t1", "steps", "rc"], args,
                  "Moving source (Rosenthal/Eagar-Tsai): pool size error vs "
                  "CPU time", "CPU seconds",
                  "max relative error of length, width, depth")


def study_dam_break(args):
    """Dam break (tests/dam_break.cc, point shifting 2, volume correction
    0.5, free-slip floor): cells per column width a x FLIP fraction x
    Courant number; error: relative front-speed error after the release
    phase against Martin & Moyce (what the test gates)."""
    points = []
    for n in (8, 16, 32, 64):
        for flip in ((0.9, 0.95, 0.99) if n < 64 else (0.95,)):
            for cfl in ((0.125, 0.25, 0.5) if n < 64 else (0.25, 0.5)):
                points.append(("n%d_f%g_c%g" % (n, flip, cfl),
                               [str(n), "-", "2", "0.5", "slip", str(cfl),
                                str(flip)],
                               {"n_per_a": n, "flip": flip, "courant": cfl,
                                "label": "a/%d f%g C%g" % (n, flip, cfl)}))
    rows = run_test_sweep(args, "dam_break", "test_dam_break", points)
    for r in rows:
        log = r.pop("log")
        m = re.search(r"unrounded: front speed.*", log)
        text = m.group(0) if m else ""
        r["front_speed"] = number(r"unrounded: front speed for T >= 1.19 " + NUM,
                                  text)
        r["error"] = number(r"relative front speed deviation " + NUM, text)
        r["height_error"] = number(r"max relative height deviation " + NUM,
                                   text)
        r["height_error_early"] = number(r"for t sqrt\(g/a\) <= 2.7 " + NUM,
                                         text)
        r["front_error"] = number(r"max relative front deviation " + NUM, text)
        r["steps"] = number(r"fluid steps = ([0-9]+)", log)
    write_outputs("dam_break", rows,
                  ["n_per_a", "flip", "courant", "cpu_s", "wall_s", "error",
                   "front_speed", "height_error", "height_error_early",
                   "front_error", "steps", "rc"], args,
                  "Dam break: front speed error (T >= 1.19) vs CPU time",
                  "CPU seconds", "|dZ/dT / Martin-Moyce - 1|")
    # The column height (converging with the cell size, where the front
    # speed is not: doc/speed_accuracy.md) as a second chart.
    svg_loglog(os.path.join(args.img, "study_dam_break_height.svg"), rows,
               "cpu_s", "height_error", "label",
               "Dam break: max column-height error vs CPU time", "CPU seconds",
               "max |H / Martin-Moyce - 1|")


def study_static_droplet(args):
    """Static 2D drop (tests/static_droplet.cc with the solver defaults):
    R/h x FLIP fraction x capillary step fraction, to 2.5 capillary times;
    error: relative Laplace jump error of the mean inside pressure."""
    points = []
    for r_h in (5, 10, 20, 40):
        for flip in (0.9, 0.95, 0.99):
            for c in (0.25, 0.5, 1.0):
                points.append(("R%g_f%g_c%g" % (r_h, flip, c),
                               [str(r_h), str(flip), str(c)],
                               {"R_over_h": r_h, "flip": flip,
                                "step_fraction": c,
                                "label": "R%gh f%g c%g" % (r_h, flip, c)}))
    rows = run_test_sweep(args, "static_droplet", "test_static_droplet", points)
    for r in rows:
        text = r.pop("log")
        r["error"] = number(r"unrounded: Laplace jump error " + NUM, text)
        r["capillary_number"] = number(r"mu u_max/sigma " + NUM + ",", text)
        r["steps"] = number(r", steps ([0-9]+)", text)
    write_outputs("static_droplet", rows,
                  ["R_over_h", "flip", "step_fraction", "cpu_s", "wall_s",
                   "error", "capillary_number", "steps", "rc"], args,
                  "Static droplet: Laplace jump error vs CPU time",
                  "CPU seconds", "|p_in / (sigma/R) - 1|")


def adaptive_block(r_max, s_min=1, s_max=1e4):
    """The Solid entries of the adaptive mass scaling (appended to a scene:
    a subsection may be opened again)."""
    return ("\nsubsection Solid\n  set Mass scaling = adaptive\n"
            "  subsection Adaptive mass scaling\n"
            "    set Maximum kinetic energy ratio = %g\n"
            "    set Minimum factor = %g\n    set Maximum factor = %g\n"
            "  end\nend\n" % (r_max, s_min, s_max))


def coupled_scene(factor, args):
    """prm/single_track_coupled.prm cut to a 120 x 80 x 144 um box around the
    start of the track and its first microsecond (the solid's mass-scaling
    effects show there first: the surface under the beam heats at ~3e9 K/s
    and expands at ~1 m/s, doc/speed_accuracy.md)."""
    base = open(os.path.join(ROOT, "prm", "single_track_coupled.prm")).read()
    probes = "; ".join("%ge-6,80e-6,%ge-6" % (x, z)
                       for x in (52, 60, 68) for z in (92, 84, 76, 68))
    return set_parameters(base, {
        "Time stepping/End time": "1e-6",
        "Background grid/Lower corner": "0, 40e-6, 0",
        "Background grid/Upper corner": "120e-6, 120e-6, 144e-6",
        "Laser/End point": "110e-6, 80e-6, 0",
        "Solid/Mass scaling factor": "%g" % factor,
        "Solid/Probe points": probes,
        "Solid FEM/Zone lower corner": "0, 40e-6, 0",
        "Solid FEM/Zone upper corner": "120e-6, 120e-6, 48e-6",
        "Output/Directory": "out",
        "Output/Output interval": "0",
        "Output/Write material points": "never",
        "Output/Probe points": "60e-6,80e-6,92e-6",
    })


def study_mass_scaling(args):
    exe = os.path.abspath(os.path.join(args.build, "femp"))
    if not os.path.exists(exe):
        raise SystemExit("study.py: build %s first" % exe)
    rows = []
    # Fixed factors, then the adaptive controller (starting at s = 1, range
    # [1, 1e4]) with four targets r_max of K / U_el.
    points = [(f, None) for f in (1, 3, 10, 100, 1000, 10000)] + \
        [(1, r) for r in (0.0005, 0.001, 0.002, 0.01)]
    for f, r_max in points:
        def make(d, f=f, r_max=r_max):
            with open(os.path.join(d, "scene.prm"), "w") as fh:
                fh.write(coupled_scene(f, args) +
                         (adaptive_block(r_max) if r_max else ""))
            cmd = [exe, "scene.prm"]
            if args.np > 1:
                cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe",
                       "-np", str(args.np)] + cmd
            rc, cpu, wall = run_timed(cmd, d, os.path.join(d, "log.txt"))
            r = {"rc": rc, "cpu_s": cpu, "wall_s": wall}
            try:
                r.update(solid_run_figures(os.path.join(d, "out")))
            except (OSError, ValueError, StopIteration, KeyError,
                    IndexError) as ex:
                r["read_error"] = str(ex)
            return r
        name = "f%g" % f if r_max is None else "adaptive_r%g" % r_max
        r = cached(os.path.join(args.out, "mass_scaling", name), make)
        r.update(factor=f if r_max is None else "adaptive",
                 r_max=r_max or "",
                 label="s=%g" % f if r_max is None else "adapt r=%g" % r_max)
        rows.append(r)
    ref = rows[0].get("sxx")
    for r in rows:
        s = r.get("sxx")
        if ref and s and len(s) == len(ref) and r["rc"] == 0:
            num = sum((a - b) ** 2 for a, b in zip(s, ref))
            den = sum(b * b for b in ref)
            r["error"] = math.sqrt(num / den) if den > 0 else None
        else:
            r["error"] = None
        if r is rows[0]:
            r["error"] = None  # the reference itself
            r["reference"] = True
    write_outputs("mass_scaling", rows,
                  ["factor", "r_max", "cpu_s", "wall_s", "error", "solid_steps",
                   "stress_work", "transfer", "remap", "max_k_over_i",
                   "max_k_over_el", "s_min", "s_max", "s_end", "k_jump",
                   "balance", "rc"],
                  args, "Solid mass scaling: sigma_xx vs factor 1, reduced "
                  "coupled track", "CPU seconds", "relative RMS sigma_xx error")


def probe_line_differences(run_out, ref_out, lines=("CD", "EF", "cross"),
                           field="sigma_xx", t_min=1e-4):
    """Largest |field(run) - field(ref)| / max |field(ref)| per probe line
    and field output of equal time (>= t_min), as {line: [(t, d)]}."""
    def load(path):
        t = femp_post.read_csv(path)
        return t.time, t[field].tolist()
    out = {}
    for ln in lines:
        for p in sorted(os.listdir(ref_out)):
            if not (p.startswith("probe_line_%s_" % ln) and p.endswith(".csv")):
                continue
            q = os.path.join(run_out, p)
            if not os.path.exists(q):
                continue
            t0, a = load(os.path.join(ref_out, p))
            t1, b = load(q)
            if t0 < t_min or abs(t0 - t1) > 1e-9 or len(a) != len(b):
                continue
            peak = max(abs(v) for v in a)
            d = max(abs(v - w) for v, w in zip(a, b))
            out.setdefault(ln, []).append((t0, d / peak if peak > 0 else 0.))
    return out


def study_solid_step(args):
    exe = os.path.abspath(os.path.join(args.build, "femp"))
    if not os.path.exists(exe):
        raise SystemExit("study.py: build %s first" % exe)
    scene = os.path.join(ROOT, "prm", "case_3_2_cooling.prm")
    # Pairs of equal sqrt(s) / C (s = 400, C = 1 and s = 100, C = 0.5;
    # s = 2540, C = 0.8 and s = 1000, C = 0.5): the number that the answer
    # depends on (doc/speed_accuracy.md, "The solid's safety factor").
    points = [(100, 0.5), (100, 1.0), (400, 1.0), (1000, 0.3162), (1000, 0.5),
              (1000, 0.7), (1000, 0.8), (1000, 1.0), (2540, 0.8)]
    rows = []
    for s, c in points:
        def make(d, s=s, c=c):
            # The scene's switch of the safety factor after solidification
            # off: every run keeps its (s, C) to the end.
            cmd = [exe, "--set", "Physics/Melt flow=false",
                   "--set", "Output/Write material points=never",
                   "--set", "Solid/Safety factor after solidification=0",
                   "--set", "Solid/Mass scaling factor=%g" % s,
                   "--set", "Solid/Safety factor=%g" % c,
                   "--set", "Output/Directory=out", scene]
            if args.np > 1:
                cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe",
                       "-np", str(args.np)] + cmd
            rc, cpu, wall = run_timed(cmd, d, os.path.join(d, "log.txt"))
            r = {"rc": rc, "cpu_s": cpu, "wall_s": wall}
            log = open(os.path.join(d, "log.txt")).read()
            m = re.search(r"Solid: (\d+) steps of ([0-9.e+-]+) s", log)
            if m:
                r["solid_steps"], r["solid_dt"] = int(m.group(1)), float(m.group(2))
            m = re.search(r"stress work ([0-9.e+-]+), kinetic [^,]+, hourglass "
                          r"[^,]+, balance ([0-9.e+-]+)", log)
            if m:
                r["stress_work"], r["balance"] = float(m.group(1)), float(m.group(2))
            return r
        name = "s%g_c%g" % (s, c)
        r = cached(os.path.join(args.out, "solid_step", name), make)
        r.update(factor=s, safety=c, eta=round(math.sqrt(s) / c, 1),
                 label="s=%g C=%g" % (s, c),
                 dir=os.path.join(args.out, "solid_step", name))
        rows.append(r)
    ref_out = os.path.join(rows[0]["dir"], "out")
    for r in rows:
        diffs = probe_line_differences(os.path.join(r["dir"], "out"), ref_out)
        for ln in ("CD", "EF", "cross"):
            v = [d for _, d in diffs.get(ln, [])]
            r["max_" + ln] = round(max(v), 4) if v else ""
            r["end_" + ln] = round(v[-1], 4) if v else ""
        worst = [r["max_" + ln] for ln in ("CD", "EF", "cross")
                 if r["max_" + ln] != ""]
        r["error"] = max(worst) if worst and r["rc"] == 0 else None
        if r is rows[0]:
            r["error"] = None
            r["reference"] = True
    write_outputs("solid_step", rows,
                  ["factor", "safety", "eta", "cpu_s", "wall_s", "solid_steps",
                   "solid_dt", "error", "max_CD", "max_EF", "max_cross",
                   "end_CD", "end_EF", "end_cross", "stress_work", "balance",
                   "rc"],
                  args, "Solid mass scaling x safety factor: sigma_xx on the "
                  "probe lines vs s = 100, C = 0.5, reduced track + cooling",
                  "CPU seconds", "largest sigma_xx difference / peak")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("study", choices=["stefan", "mass_scaling", "danilovskaya", "physics", "droplet", "track",
                             "track_surface", "rosenthal", "dam_break", "static_droplet",
                             "solid_step"])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "study"),
                    help="folder for run directories and CSV")
    ap.add_argument("--img", default=os.path.join(ROOT, "doc", "img"))
    ap.add_argument("--np", type=int, default=1, help="MPI ranks of femp runs")
    args = ap.parse_args()
    {"stefan": study_stefan, "mass_scaling": study_mass_scaling,
     "danilovskaya": study_danilovskaya, "physics": study_physics,
     "droplet": study_droplet, "track": study_track,
     "track_surface": study_track_surface,
     "rosenthal": study_rosenthal, "dam_break": study_dam_break,
     "static_droplet": study_static_droplet,
     "solid_step": study_solid_step}[args.study](args)


if __name__ == "__main__":
    main()
