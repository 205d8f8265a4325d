#!/usr/bin/env python3
"""Melt pools of femp against published single-track experiments
(doc/validation.md).

  contrib/validate.py scenes   [--check]
  contrib/validate.py run      [--cases REGEX] [--setting S] [--np N]
                               [--set 'SECTION/ENTRY=VALUE' ...]
                               [--build build] [--out build/validation]
                               [--max-wall SECONDS] [--checkpoint-minutes M]
                               [--restart-after-checkpoint]
  contrib/validate.py resume-check [--cases REGEX] [--build build]
                               [--out build/validation_resume]
  contrib/validate.py reevaluate [--out build/validation]
  contrib/validate.py report   [--out build/validation] [--img doc/img]
  contrib/validate.py all      (run, then report; the ctest 'validation')
  contrib/validate.py pipeline --expected FILE [--build build]
  contrib/validate.py regime
  contrib/validate.py width    [--out build/validation] [--cases REGEX]
  contrib/validate.py conduction
  contrib/validate.py spots    [--cases REGEX] [--end-time T] [--np N]
  contrib/validate.py conduction3d [--cases REGEX] [--h 8,4] [--eta A]
                               [--props file,nolatent,const] [--evap]
  contrib/validate.py dig      [--out build/validation] [--cases REGEX]
                               [--settings REGEX] [--force]

scenes: writes prm/validation/<case>.prm, one scene per measured case of
  the data sets in prm/validation/data/ (each file names its publication):
  bare plate at the stated temperature, beam radius r_b = D4sigma / 2 (the
  1/e^2 radius of a Gaussian), ray-traced absorption with the alloy's
  optical constants from its material file, melt flow with recoil, 8 um
  cells. --check: fail if a written scene differs from the committed one.
run: runs the scenes matching REGEX (default: the AM-Bench tracks, the
  NIST spot sweep and the Trapp subset, see DEFAULT_CASES) with femp's
  default free surface ('default') or the fine-surface setting ('fine':
  height-function curvature, 2 smoothing passes, point shifting 2), one
  run directory per case and setting under --out; a run whose result.json
  exists is skipped (resumable). Variants for the domain-size check: setting 'large' (the
  domain 1.5 x wider and deeper); for the resolution study: 'h4' and 'h2'
  (4 and 2 um cells instead of 8, points at half the cell size, the ray
  lattice refined with the cells) and 'compact' (a shorter track on a
  smaller plate: 3 measured widths rounded down to 8 um, at least 160 um;
  the plate 40 um before and 80 um after it, the width + 80 um across,
  1.6 depths + 48 um below the surface, at least 96 um; Trapp 48 W: a
  200 um track on 320 x 160 x 96 um, about a quarter of the rule's cells and
  5/8 of its path; the evaluation windows follow the shorter path), e.g.
  'h2+compact' for the 2 um point; 'long' (the track twice as long, the
  plate with it, the pool measured from a third of that track on; the
  evaluation windows follow the longer path: whether the pool is steady);
  diagnostics 'thermal' (no melt flow) and
  'nomarangoni' (d sigma/dT = 0); 'evapmass' (the evaporated mass leaves
  the melt: Heat transfer/Remove evaporated mass = true); 'film' (the
  recoil-driven melt film slips along the solid: Melt flow/Front wall
  film = true); 'piston' (the sub-cell film between the boiling surface
  and the melting front: Heat transfer/Front wall piston = true); 'expel'
  (the melt of boiling surface cells leaves at the Bernoulli speed of
  their recoil: Melt flow/Front wall expulsion = true); 'surfactant'
  (316L only: dsigma/dT from the surfactant model with the sulphur
  activity from Pichler et al.'s slope, Melt flow/Surface tension model =
  surfactant) and 'linear' (the constant dsigma/dT); 'kulr19' (the KU
  Leuven tracks, kul_*, with their 37.5 um spot read as the 1/e^2
  diameter, r_b 18.75 um, instead of the radius); 'a+b'
  combines them (e.g. 'h4+fine'). Any other setting name with --set
  overrides runs the scenes with those femp parameters (e.g. --setting
  cell --set 'Melt flow/Recoil temperature=cell').
  A long run goes in segments: with --checkpoint-minutes M femp writes a
  checkpoint every M minutes of wall time into <run>/checkpoint (femp keeps
  the last two); a run stopped before its end (--max-wall, a kill) leaves
  no result.json, and the same command resumes it from its latest
  checkpoint (it refuses a checkpoint of another scene or other
  parameters). segments.json records each segment (its start, the
  checkpoint it resumed from, wall and CPU time, exit code, the simulated
  time reached; a killed segment keeps its last record, written every
  minute), log.txt holds the logs of all segments; result.json's wall and
  CPU times are their sums. --restart-after-checkpoint ends femp after each
  checkpoint it writes before the end and resumes in a new process
  (each segment a fresh process), e.g. the 2 um track, in segments of a
  few hours each:
    contrib/validate.py run --np 1 --cases '^trapp_048W$' --setting h2 \
        --checkpoint-minutes 20 --restart-after-checkpoint
resume-check: a run in segments against the same run straight through
  (default Trapp 32 W, 8 um, about a minute): 'straight' (no checkpoints),
  'checkpointed' (a checkpoint every third of the path, straight through),
  'segmented' (the same checkpoints, its first segment stopped at the
  first one and resumed) and 'restarted' (the same with
  --restart-after-checkpoint: three segments). femp's restart is
  bit-identical, so 'segmented' and 'restarted' must give the numbers of
  result.json and the time series of 'checkpointed' exactly (exit 1 on a
  difference); 'straight' differs from
  them within the pressure solver's tolerance (a checkpoint restarts its
  preconditioner), printed.
report: reads every finished run under --out and writes their tables to
  <out>/tables.md (printed too; doc/validation.md takes them by hand) and
  the figures to --img (SVG, standard library only); the NIST spot sweep
  has its own two figures (femp against measured; width and depth against
  the spot). Only the runs under --out appear: the figures hold no run
  from elsewhere, and doc/validation.md is not written.
width: what sets each finished run's fusion width (its last field
  output): the widest section's distance behind the beam, the temperature
  on the axis there, the melt's surface flow across the track, and the
  widest fusion width read on the top substrate row of cells (h/2 below
  the surface) and at the original surface (the temperature extrapolated
  from the two top rows, as femp's melt_pool.csv reads it); 'near96':
  melt_pool.csv's fusion width read again (a numpy copy of femp's
  isotherm box) on the cells from 96 um behind the beam on only, at each
  field output in the last 40 % of the path, median (the number of
  outputs in brackets): the pool near the beam, without the tail that
  melt driven back along the track may keep wide at the measured
  region's start. The reported width stays melt_pool.csv's median.
conduction: the Eagar-Tsai (pure conduction) fusion width and depth of
  the Trapp conduction tracks with the measured absorptivity and constant
  properties (averaged over 293 K..T_s, and at T_s), and the width h/2
  below the surface (where the top row of cells of size h reads it).
conduction3d: an independent reference for femp's conduction (numpy
  finite volumes, explicit, k(T), c_p(T) and latent heat from the material
  file, exact Gaussian source on the top faces, the measured absorptivity,
  no flow, no losses; with --evap femp's evaporation loss on the top face)
  on the scene's plate and path: the fusion width on the top row of cells
  and at the surface, the depth, and the hottest top-row and surface
  temperatures, at cell sizes h.
spots: Simonds' stationary spots (default 626, 463 and 378 W) for the
  first part of the pulse on a plate cut to 0.64 x 0.64 x 0.30 mm: the
  melt onset and the times the absorbed fraction reaches 0.35, 0.45, 0.6
  (the depression's rise) against the measured melt and keyhole onsets
  (resumable: a run with a time series is only evaluated); the figure
  validation_simonds_absorption.svg (--img) of every finished spot: the
  absorbed fraction against time with the measured keyhole onsets.
dig: what digs the pool, from the field outputs of finished runs (read
  with contrib/femp_post.py; VTU or HDF5): per output the depression depth
  below the original surface, the surface temperature and recoil pressure
  at its deepest point and at the hottest surface cell, the melt thickness
  under the hottest cell (to the solidus, along the surface normal and
  vertically), the front wall's angle from the vertical, the drilling
  speed (d depth / dt), the fastest melt, and the evaporated power against
  the absorbed power (absorption.csv); then the medians over the last 40 %
  of the path, the drilling phase and the run's evaporation share from
  femp's energy line. Writes dig.csv into each run directory and a 'dig'
  entry into its result.json (resumable: a dig.csv newer than the outputs
  is reread). The outputs must be at most 10 us apart: run the case with
  '--setting dig' (fields every 5 us, HDF5), e.g.
    contrib/validate.py run --np 2 --cases '^trapp_099W$' --setting dig
    contrib/validate.py run --np 2 --cases '^trapp_099W$' --setting h4+dig \
        --set 'Time stepping/End time=1.6e-4'     # a window at 4 um
    contrib/validate.py dig --cases '^trapp_099W$'
regime: the normalized enthalpy of every measured track (as femp's scene
  log computes it) with the flat-surface Fresnel absorptivity, the measured
  one and 0.35, beside the measured depth/width.
pipeline: a small, fast case (the Trapp 48 W track, thermal only, 16 um
  cells, 0.2 ms) through the whole chain: scene, femp, melt_pool.csv and
  absorption.csv, errors against the measurement; prints rounded numbers
  and compares them with FILE (exit 1 on a difference).

Fusion zone: the width and depth of the metal above the solidus inside the
plate ('width_solidus_substrate', 'depth_solidus_substrate' of
melt_pool.csv), the median over the last 40 % of the laser's path (the
quasi-steady pool; its maximum there is written too). Absorbed fraction:
the time mean of absorption.csv's 'absorbed_fraction' over the same window.
Retained fraction (Trapp's table and the absorption figure, retained()):
the absorbed fraction times 1 - surface losses / absorbed energy of
femp's energy line, the heat the plate keeps, which calorimetry measures.
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
import femp_post  # noqa: E402  (CSV series and logs; numpy for fields)

DATA = os.path.join(ROOT, "prm", "validation", "data")
SCENES = os.path.join(ROOT, "prm", "validation")

# Cases run by 'run' without --cases (the cost budget of the validation):
# all seven AM-Bench tracks, the six tracks of the NIST spot sweep and the
# Trapp series from 32 to 178 W (conduction, transition and keyhole).
DEFAULT_CASES = r"^(amb_.*|nist_spot_.*|trapp_(032|048|065|083|099|134|178)W)$"

FINE = {"Melt flow/Curvature": "height function",
        "Melt flow/Curvature smoothing": "2",
        "Melt flow/Point shifting": "2"}


def refined(h):
    """The resolution study's settings: cell size h, points at h/2 and the
    ray lattice refined with the cells (a ray per 7.5 um at 8 um cells, 4
    rays per 30 um beam radius; 8 and 16 rays per radius at 4 and 2 um).
    The scene's geometry is a multiple of 8 um, so it stays the same."""
    return {"Background grid/Cell size": fmt(h),
            "Material points/Point spacing": fmt(h / 2),
            "Laser/Rays per beam radius": "%d" % round(4 * 8e-6 / h)}


# Named settings of 'run' (their femp parameters; --set adds to them).
# 'large' is the domain-size check (the scene 1.5 x wider and deeper);
# 'compact' the compact domain (a shorter track on a smaller plate).
SETTINGS = {"default": {}, "large": {}, "compact": {}, "long": {},
            "fine": FINE}

H = 8e-6          # cell size, m
GAS = 48e-6       # gas above the plate, m
MARGIN_START = 80e-6   # plate before the track's start, m
MARGIN_END = 160e-6    # plate after the track's end, m
COMPACT_START = 40e-6  # the compact domain's plate before the track, m
COMPACT_END = 80e-6    # the compact domain's plate after the track, m
# A run has reached its end when its last time is within this fraction of
# the path's end: the scene writes the end time with 6 significant digits
# (fmt()), up to 5e-6 of it below the path's Ltr / v.
END_RTOL = 1e-5
# Beam radius of the KU Leuven tracks (Coen et al. 2022), m: the data do
# not give the spot; a related paper of the group gives 37.5 um, taken as
# the 1/e^2 radius (D4sigma 75 um). The other reading (a 37.5 um 1/e^2
# diameter) is run by --setting kulr19 (KUL_SETTINGS).
KUL_RB = 37.5e-6


# ---------------------------------------------------------------- data
def read_table(name):
    """Rows of a data file (comment lines '#' skipped; the first
    non-comment line is the header; a second section after a comment line
    that follows data is ignored)."""
    rows, header = [], None
    with open(os.path.join(DATA, name)) as fh:
        for line in fh:
            line = line.strip()
            if not line:
                continue
            if line.startswith("#"):
                if rows:
                    break
                continue
            cells = next(csv.reader([line]))
            if header is None:
                header = cells
            else:
                rows.append(dict(zip(header, cells)))
    return rows


def num(s):
    try:
        return float(s)
    except (TypeError, ValueError):
        return None


def ceil_cells(x, h=H):
    return h * math.ceil(x / h - 1e-9)


def cases():
    """Every measured case as a dict: name, data set, alloy, P (W), v
    (m/s), r_b (m), T0 (K), measured width/depth (m) with their spread
    (m; SD, or the expanded uncertainty where given), absorptivity."""
    out = []
    for r in read_table("amb2022_03_in718_tracks.csv"):
        out.append(dict(
            name="amb_%s" % r["case"].replace(".", "_"), dataset="AM-Bench 2022",
            alloy="IN718", P=num(r["power_W"]), v=num(r["speed_mm_s"]) * 1e-3,
            rb=num(r["d4sigma_um"]) * 0.5e-6, T0=296.65,
            width=num(r["width_um"]) * 1e-6, width_sd=num(r["width_sd_um"]) * 1e-6,
            depth=num(r["depth_um"]) * 1e-6, depth_sd=num(r["depth_sd_um"]) * 1e-6,
            label="case %s" % r["case"],
            note="AMB2022-03 case %s: %s W, %s mm/s, D4sigma %s um" % (
                r["case"], r["power_W"], r["speed_mm_s"], r["d4sigma_um"])))
    for r in read_table("nist_in718_spot_sweep.csv"):
        tag = ("eos" if r["machine"].startswith("EOS") else "ammt")
        out.append(dict(
            name="nist_spot_%s_%03d" % (tag, round(num(r["spot_um"]))),
            dataset="NIST spot sweep", alloy="IN718", P=285.0, v=0.96,
            rb=num(r["spot_um"]) * 0.5e-6, T0=296.65,
            width=num(r["width_um"]) * 1e-6, width_sd=num(r["width_u_k2_um"]) * 1e-6,
            depth=num(r["depth_um"]) * 1e-6, depth_sd=num(r["depth_u_k2_um"]) * 1e-6,
            label="%s, spot %s µm" % (r["machine"], r["spot_um"]),
            note="NIST spot sweep, %s, spot %s um (D4sigma taken), 285 W, "
                 "960 mm/s" % (r["machine"], r["spot_um"])))
    for r in read_table("trapp2017_316l.csv"):
        P = num(r["power_W"])
        out.append(dict(
            name="trapp_%03dW" % round(P), dataset="Trapp 2017", alloy="316L",
            P=P, v=num(r["speed_mm_s"]) * 1e-3, rb=30e-6, T0=293.15,
            width=num(r["width_um"]) * 1e-6, width_sd=3e-6,
            depth=num(r["depth_um"]) * 1e-6, depth_sd=3e-6,
            absorptivity=num(r["absorptivity"]), disc=500e-6,
            label="%g W" % P,
            note="Trapp et al. 2017, %g W, 500 mm/s, 60 um 1/e^2 diameter, "
                 "0.5 mm disc" % P))
    for r in read_table("kuleuven_316l_tracks.csv"):
        # Secondary data set (trends only): the spot size is not in the
        # data; 37.5 um, which a related paper of the group gives, is taken
        # as the 1/e^2 radius (D4sigma 75 um). The plate is taken bare and
        # at room temperature, as in the other track scenes.
        P, v = num(r["power_W"]), num(r["speed_mm_s"])
        out.append(dict(
            name="kul_%03dW_%04d" % (round(P), round(v)),
            dataset="KU Leuven 2022", alloy="316L", P=P, v=v * 1e-3,
            rb=KUL_RB, T0=293.15,
            width=num(r["width_um"]) * 1e-6, width_sd=None,
            depth=num(r["depth_um"]) * 1e-6, depth_sd=None,
            regime=r["regime"], label="%g W, %g mm/s" % (P, v),
            note="Coen et al. 2022 (KU Leuven), %g W, %g mm/s, 37.5 um taken "
                 "as the 1/e^2 radius (not in the data; trends only)" % (P, v)))
    for r in read_table("simonds2018_316l_spot.csv"):
        P = num(r["power_W"])
        out.append(dict(
            name="simonds_%03dW" % round(P), dataset="Simonds 2018",
            alloy="316L", P=P, v=0.0, rb=151.5e-6, T0=293.15,
            coupling=num(r["coupling"]), t_keyhole_ms=num(r["t_keyhole_ms"]),
            t_melt_ms=num(r["t_melt_ms"]),
            weld_w=num(r["weld_W_um"]), label="%g W" % P,
            note="Simonds et al. 2018, stationary 10 ms, %g W, top-hat 303 um "
                 "(Gaussian of the same D4sigma)" % P))
    return out


# ---------------------------------------------------------------- scenes
def track_geometry(c, compact=False, length=1):
    """Domain and track of a track case. The rule (the same for every
    case): the track is 3 measured widths long (at least 320 um); the plate extends 80 um
    before and 160 um after it, 2 widths + 80 um across and 1.6 depths +
    80 um below the surface (at least 160 um; at most the disc of Trapp's
    experiment, 0.5 mm, whose bottom is then insulated as in the
    calorimetry); 48 um of gas above. melt_pool.csv measures the pool
    from a third of the track on (scene_text()). The domain-size check
    (setting 'large') shows what this rule costs in accuracy. @p compact: the
    compact domain (compact_geometry()). @p length: the track (and the
    plate with it) that many times longer, the margins and the plate's
    section unchanged (setting 'long': how far the pool is from steady)."""
    if compact:
        return compact_geometry(c, length)
    Ltr = length * ceil_cells(max(320e-6, 3 * c["width"]))
    Lx = ceil_cells(MARGIN_START + Ltr + MARGIN_END)
    Ly = 2 * ceil_cells(max(120e-6, c["width"] + 40e-6))
    Hp = ceil_cells(max(160e-6, 1.6 * c["depth"] + 80e-6))
    disc = c.get("disc")
    if disc is not None and Hp >= disc:
        Hp, bottom = disc, False
    else:
        bottom = True
    return dict(Ltr=Ltr, Lx=Lx, Ly=Ly, Hp=Hp, fixed_bottom=bottom,
                start=MARGIN_START)


def is_compact(setting):
    """Whether a setting (named settings joined by '+') has the compact
    domain."""
    return "compact" in setting.split("+")


def track_length(setting):
    """How many times the scene's track a setting runs: 2 with 'long' among
    its named settings, else 1."""
    return 2 if "long" in setting.split("+") else 1


def path_time(c, setting="default"):
    """The laser path's duration of track case @p c in @p setting, s: the
    end of the run and of the evaluation windows."""
    return track_geometry(c, is_compact(setting),
                          track_length(setting))["Ltr"] / c["v"]


def compact_geometry(c, length=1):
    """The compact domain of a track case (setting 'compact'), for the
    finest cells: the track 3 measured widths long rounded down to 8 um
    (at least 160 um), the plate 40 um before and 80 um after it, the
    measured width + 80 um across (rounded up to 16 um), 1.6 depths + 48 um
    below the surface (at least 96 um) with the bottom held at the plate
    temperature (Trapp's disc with its insulated bottom where this reaches
    it, as in the rule); 48 um of gas above. Trapp 48 W: a 200 um track on
    a 320 x 160 x 96 um plate (the rule: 320 um on 560 x 240 x 160 um).
    The evaluation windows follow its path (path_time()); the pool is
    measured from a third of the track on, as on the rule's domain (at
    4 um cells the 40 um of plate before the track stay hot and would be
    read as the widest section)."""
    Ltr = length * max(160e-6, H * math.floor(3 * c["width"] / H + 1e-9))
    Ly = 2 * ceil_cells(0.5 * c["width"] + 40e-6)
    Hp = ceil_cells(max(96e-6, 1.6 * c["depth"] + 48e-6))
    disc = c.get("disc")
    bottom = disc is None or Hp < disc
    return dict(Ltr=Ltr, Lx=ceil_cells(COMPACT_START + Ltr + COMPACT_END),
                Ly=Ly, Hp=Hp if bottom else disc, fixed_bottom=bottom,
                start=COMPACT_START)


def fmt(x):
    return "%.6g" % x


SETTINGS.update({"h4": refined(4e-6), "h2": refined(2e-6),
                 # diagnostics of what sets the width (not validation
                 # settings): no melt flow; no Marangoni stress
                 "thermal": {"Physics/Melt flow": "false"},
                 "nomarangoni": {
                     "Melt flow/Surface tension temperature derivative": "0"},
                 # the evaporated metal leaves the melt (the surface recedes
                 # by the evaporated mass flux over the density)
                 "evapmass": {"Heat transfer/Remove evaporated mass": "true"},
                 # sub-cell slip of the recoil-driven melt film on the
                 # solid (Melt flow/Front wall film, doc/flow.md)
                 "film": {"Melt flow/Front wall film": "true"},
                 # sub-cell film between the boiling surface and the
                 # melting front (Heat transfer/Front wall piston,
                 # doc/equations.md)
                 "piston": {"Heat transfer/Front wall piston": "true"},
                 # sub-cell expulsion of the melt of boiling surface cells
                 # at the recoil's Bernoulli speed (Melt flow/Front wall
                 # expulsion, doc/flow.md)
                 "expel": {"Melt flow/Front wall expulsion": "true"},
                 # dsigma/dT of 316L from the surfactant model (Sahoo et
                 # al. 1988, Fe-S constants) with the sulphur activity that
                 # reproduces Pichler et al.'s slope over 1700-2200 K
                 # (doc/flow.md "Surface tension model"; 316L cases only),
                 # and the linear model explicitly
                 "surfactant": {
                     "Melt flow/Surface tension model": "surfactant",
                     "Melt flow/Surfactant/Activity": "0.02313"},
                 "linear": {"Melt flow/Surface tension model": "linear"},
                 # the KU Leuven tracks' other spot reading: 37.5 um as the
                 # 1/e^2 diameter (r_b 18.75 um) instead of the radius
                 # (KUL_RB); the scene's domain stays that of the measured
                 # pool (kul_* cases only)
                 "kulr19": {"Laser/Beam radius": fmt(KUL_RB / 2)}})


def csv_rows(path):
    """The rows of a CSV file ('#' comment lines skipped) as dicts of strings."""
    with open(path) as f:
        lines = [line for line in f if line.strip() and not line.startswith("#")]
    return list(csv.DictReader(lines))


def setting_parameters(setting):
    """The femp parameters of a setting; 'a+b' combines named settings
    (e.g. 'h4+fine'); a name not in SETTINGS has none (--set gives them)."""
    sets = {}
    for part in setting.split("+"):
        sets.update(SETTINGS.get(part, {}))
    return sets


def material_comment(alloy):
    return {"IN718": "IN718 (thermal, melt-flow, evaporation and optical data, "
                     "each with its source)",
            "316L": "316L (thermal, melt-flow, evaporation and optical data, "
                    "each with its source)"}[alloy]


def scene_text(c, scale=1.0, compact=False, length=1):
    """The scene of case @p c; @p scale > 1 enlarges the domain across and
    below (the domain-size check); @p compact: the compact domain
    (compact_geometry()); @p length: the track that many times longer
    (track_geometry())."""
    if c["v"] == 0:
        return spot_scene_text(c)
    g = track_geometry(c, compact, length)
    Ly = 2 * ceil_cells(0.5 * g["Ly"] * scale)
    Hp = g["Hp"] if not g["fixed_bottom"] else ceil_cells(g["Hp"] * scale)
    Lx = g["Lx"]
    ztop = Hp
    t_end = g["Ltr"] / c["v"]
    fixed = ("z-: %s" % fmt(c["T0"])) if g["fixed_bottom"] else ""
    lines = [
        "# femp validation scene (doc/validation.md), written by",
        "# contrib/validate.py scenes: %s." % c["note"],
        "# Bare plate at %s K, no powder; beam radius r_b = D4sigma/2 = %s um "
        "(1/e^2)." % (fmt(c["T0"]), fmt(c["rb"] * 1e6)),
        "# Track %s um long (%s ms), plate %s x %s um, %s um thick%s; %s um "
        "cells." % (fmt(g["Ltr"] * 1e6), fmt(t_end * 1e3), fmt(Lx * 1e6),
                    fmt(Ly * 1e6), fmt(Hp * 1e6),
                    (", bottom held at %s K" % fmt(c["T0"])) if fixed else
                    " (the disc; all faces insulated)", fmt(H * 1e6)),
        "#   mpirun -np 2 femp prm/validation/%s.prm" % c["name"],
        "set Dimension = 3",
        "",
        "# Material data of %s." % material_comment(c["alloy"]),
        "include ../materials/%s.prm" % c["alloy"],
        "",
        "subsection Physics",
        "  set Heat transfer = true",
        "  set Melt flow     = true",
        "  set Gravity       = 9.81",
        "end",
        "",
        "subsection Time stepping",
        "  set End time      = %s   # s: the laser's path" % fmt(t_end),
        "  set Time step     = 0",
        "  set Safety factor = 0.5",
        "end",
        "",
        "subsection Background grid",
        "  set Lower corner = 0, 0, 0",
        "  set Upper corner = %s, %s, %s" % (fmt(Lx), fmt(Ly), fmt(ztop + GAS)),
        "  set Cell size    = %s" % fmt(H),
        "end",
        "",
        "subsection Material points",
        "  set Point spacing      = %s" % fmt(H / 2),
        "  set Substrate top      = %s" % fmt(ztop),
        "  set Sub-cell divisions = 2",
        "  subsection Powder layer",
        "    set Layer thickness = 0",
        "  end",
        "end",
        "",
        "subsection Heat transfer",
        "  set Initial temperature = %s" % fmt(c["T0"]),
        "  set Reference temperature = %s" % fmt(c["T0"]),
        "  set Fixed temperatures  = %s" % fixed,
        "end",
        "",
        "subsection Melt flow",
        "  # Recoil: zeta_p = 0.54 (Anisimov's back-flow fraction); the alloy's",
        "  # viscosity and surface tension come from its material file.",
        "  set Recoil coefficient = 0.54",
        "  set Darcy constant     = 1e8",
        "  set Darcy epsilon      = 1e-3",
        "end",
        "",
        "subsection Laser",
        "  set Power            = %s" % fmt(c["P"]),
        "  set Beam radius      = %s" % fmt(c["rb"]),
        "  set Scan speed       = %s" % fmt(c["v"]),
        "  set Start point      = %s, %s, 0" % (fmt(g["start"]), fmt(Ly / 2)),
        "  set End point        = %s, %s, 0" % (fmt(g["start"] + g["Ltr"]),
                                                 fmt(Ly / 2)),
        "  set Start time       = 0",
        "  # Rays traced into the surface, Fresnel absorption with the",
        "  # material file's optical constants (no fitted absorptivity).",
        "  set Absorption model = ray traced",
        "end",
        "",
        "subsection Output",
        "  set Directory             = output",
        "  set Output interval       = 0",
        "  set Write material points = never",
        "  set Time series interval  = %s" % fmt(min(5e-6, t_end / 100)),
        "  # The pool and the fusion zone of melt_pool.csv from a third of",
        "  # the track on: the cross-sections of its first measured width,",
        "  # where the pool forms and the plate's start face keeps the metal",
        "  # hot, are no steady track.",
        "  set Melt pool from x      = %s" % fmt(g["start"] + g["Ltr"] / 3),
        "  set Progress interval     = 1000",
        "end",
        ""]
    return "\n".join(lines)


def spot_scene_text(c):
    """Stationary spot (Simonds 2018): 10 ms on a plate; the top-hat beam
    of 303 um is taken as the Gaussian of the same second-moment diameter
    (D4sigma = 303 um, r_b = 151.5 um): femp's beam is Gaussian, whose
    peak irradiance is then twice the top-hat's. The spot moves 10 um in
    the 10 ms (femp's line scan needs a speed)."""
    L, Hp = 1200e-6, 1120e-6
    lines = [
        "# femp validation scene (doc/validation.md), written by",
        "# contrib/validate.py scenes: %s." % c["note"],
        "# The top-hat beam is approximated by the Gaussian of the same",
        "# D4sigma (303 um, r_b = 151.5 um): its peak irradiance is twice the",
        "# top-hat's, so the keyhole may start earlier than measured. The beam",
        "# creeps 10 um in the 10 ms (a line scan needs a speed). About 3",
        "# million 8 um cells: not in the default validation run.",
        "#   mpirun -np 2 femp prm/validation/%s.prm" % c["name"],
        "set Dimension = 3",
        "",
        "# Material data of %s." % material_comment(c["alloy"]),
        "include ../materials/%s.prm" % c["alloy"],
        "",
        "subsection Physics",
        "  set Heat transfer = true",
        "  set Melt flow     = true",
        "end",
        "subsection Time stepping",
        "  set End time = 1e-2",
        "end",
        "subsection Background grid",
        "  set Lower corner = 0, 0, 0",
        "  set Upper corner = %s, %s, %s" % (fmt(L), fmt(L), fmt(Hp + 80e-6)),
        "  set Cell size    = %s" % fmt(H),
        "end",
        "subsection Material points",
        "  set Point spacing      = %s" % fmt(H / 2),
        "  set Substrate top      = %s" % fmt(Hp),
        "  set Sub-cell divisions = 2",
        "  subsection Powder layer",
        "    set Layer thickness = 0",
        "  end",
        "end",
        "subsection Heat transfer",
        "  set Initial temperature   = %s" % fmt(c["T0"]),
        "  set Reference temperature = %s" % fmt(c["T0"]),
        "  set Fixed temperatures    = z-: %s" % fmt(c["T0"]),
        "end",
        "subsection Melt flow",
        "  set Recoil coefficient = 0.54",
        "end",
        "subsection Laser",
        "  set Power            = %s" % fmt(c["P"]),
        "  set Beam radius      = %s" % fmt(c["rb"]),
        "  set Scan speed       = 1e-3",
        "  set Start point      = %s, %s, 0" % (fmt(L / 2 - 5e-6), fmt(L / 2)),
        "  set End point        = %s, %s, 0" % (fmt(L / 2 + 5e-6), fmt(L / 2)),
        "  set Absorption model = ray traced",
        "end",
        "subsection Output",
        "  set Directory             = output",
        "  set Output interval       = 0",
        "  set Write material points = never",
        "  set Time series interval  = 1e-5",
        "  set Progress interval     = 1000",
        "end",
        ""]
    return "\n".join(lines)


def material(alloy):
    """Density, c_p(T), lambda(T), solidus and n, k of a material file."""
    text = open(os.path.join(ROOT, "prm", "materials", alloy + ".prm")).read()
    get = lambda key: re.search(r"set %s\s*=\s*([^#\n]*)" % re.escape(key),
                                text).group(1).strip()

    def table(v):
        pts = [tuple(float(a) for a in p.split(":")) for p in v.split(",")]

        def f(T):
            if T <= pts[0][0]:
                return pts[0][1]
            for (a, b), (c, d) in zip(pts, pts[1:]):
                if T <= c:
                    return b + (d - b) * (T - a) / (c - a)
            return pts[-1][1]
        return f
    return dict(rho=float(get("Density")), cp=table(get("Specific heat")),
                k=table(get("Thermal conductivity")),
                Ts=float(get("Solidus temperature")),
                Tl=float(get("Liquidus temperature")),
                L=float(get("Latent heat of fusion")),
                n=float(get("Refractive index")),
                kappa=float(get("Extinction coefficient")),
                Lv=float(get("Latent heat of evaporation")),
                Tv=float(get("Evaporation temperature")),
                M=float(get("Molar mass")))


def cmd_regime(args):
    """The normalized enthalpy of every measured track as femp's log
    computes it, beside the measured depth/width."""
    print("case                  P(W)  v(m/s) r_b(um) depth/width  "
          "dH/h_s(A0)  dH/h_s(eta meas.)  dH/h_s(0.35)")
    for c in cases():
        if c["v"] == 0:
            continue
        m = material(c["alloy"])
        rc = m["rho"] * m["cp"](m["Ts"])
        D = m["k"](m["Ts"]) / rc
        base = c["P"] / (math.pi * rc * m["Ts"] * math.sqrt(D * c["v"] * c["rb"] ** 3))
        eta = c.get("absorptivity")
        print("%-20s %5.0f  %5.2f  %6.1f  %10.2f  %10.1f  %17s  %12.1f" % (
            c["name"], c["P"], c["v"], c["rb"] * 1e6, c["depth"] / c["width"],
            fresnel(m["n"], m["kappa"]) * base,
            ("%.1f" % (eta * base)) if eta else "-", 0.35 * base))


def moving_gaussian_rise(x, y, z, q, v, a, rho_cp, var_xy, var_z=0.0,
                         t_on=0.1):
    """Temperature rise (K) at (x, y, z) of a Gaussian source of power q (W)
    moving at v along +x over a half-space of constant diffusivity a and
    heat capacity rho_cp, insulated at its surface z = 0, in the frame of
    the source (x < 0 behind it, z > 0 below the surface): the superposed
    point releases q dt' at each time t' before the present one,
    T - T0 = int_0^t_on q / rho_cp g_xy g_z dt', with the lateral Gaussian
    g_xy of variance 2 a t' + var_xy (var_xy = r_b^2/4 for a beam of 1/e^2
    radius r_b) and g_z the half-Gaussian of variance 2 a t' + var_z
    mirrored at the surface (var_z = 0: a surface source). t_on: how long
    the source has been on, s (0.1 s: the quasi-steady field of the tracks
    here; the path's time: the field at its end, the source started from
    rest at x = -v t_on). Quadrature on a log grid of t'."""
    import numpy as np
    t = np.logspace(-11, math.log10(t_on), 3000)
    var = 2 * a * t + var_xy
    vz = 2 * a * t + var_z
    f = (q / rho_cp / (2 * math.pi * var)
         * np.exp(-((x + v * t) ** 2 + y * y) / (2 * var))
         * 2 / np.sqrt(2 * math.pi * vz) * np.exp(-z * z / (2 * vz)))
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(t)))


def eagar_tsai(P, eta, rb, v, k, rho, cp, T0, Ts, z_width=0.0):
    """Width (at the depth z_width below the surface, the surface by
    default) and depth (m) of the region above Ts of the Eagar-Tsai
    solution: a Gaussian surface source (1/e^2 radius rb, absorbed power
    eta P) moving at v over a half-space of constant properties
    (moving_gaussian_rise(), quasi-steady)."""
    import numpy as np
    a = k / (rho * cp)

    def temp(x, y, z):
        return T0 + moving_gaussian_rise(x, y, z, eta * P, v, a, rho * cp,
                                         rb * rb / 4)

    def extent(direction):
        best = 0.0
        for x in np.linspace(-6 * rb, 2 * rb, 161):
            if temp(x, 0, z_width if direction == "y" else 0) < Ts:
                continue
            lo, hi = 0.0, 20 * rb
            for _ in range(40):
                m = 0.5 * (lo + hi)
                ok = (temp(x, m, z_width) >= Ts if direction == "y"
                      else temp(x, 0, m) >= Ts)
                lo, hi = (m, hi) if ok else (lo, m)
            best = max(best, lo)
        return best
    return 2 * extent("y"), extent("z")


def cmd_conduction(args):
    """Pure conduction (Eagar-Tsai, constant properties, no latent heat,
    no flow) with the measured absorptivity, for the Trapp conduction
    tracks: which width the measured absorbed power gives without flow,
    with the properties averaged over T0..T_s and taken at T_s."""
    print("case         P(W) eta(meas.) | width/depth (um): measured | "
          "mean 293 K..T_s | at T_s")
    for c in cases():
        if c["dataset"] != "Trapp 2017" or c["depth"] / c["width"] > 0.5:
            continue
        m = material(c["alloy"])
        Ts, T0 = m["Ts"], c["T0"]
        Tm = [T0 + (Ts - T0) * (i + 0.5) / 100 for i in range(100)]
        k_mean = sum(m["k"](T) for T in Tm) / 100
        cp_mean = sum(m["cp"](T) for T in Tm) / 100
        out = []
        for k, cp in ((k_mean, cp_mean), (m["k"](Ts), m["cp"](Ts))):
            w, d = eagar_tsai(c["P"], c["absorptivity"], c["rb"], c["v"], k,
                              m["rho"], cp, T0, Ts)
            out.append("%5.1f / %4.1f" % (w * 1e6, d * 1e6))
        # the width read at the centre of the top substrate cell row, h/2
        # below the surface (a reading on the cell centres alone)
        rows = [eagar_tsai(c["P"], c["absorptivity"], c["rb"], c["v"], k_mean,
                           m["rho"], cp_mean, T0, Ts, z_width=h / 2)[0]
                for h in (8e-6, 4e-6)]
        print("%-12s %4.0f %6.3f      | %5.1f / %4.1f              | %s "
              "(k %.1f, c_p %.0f) | %s (k %.1f, c_p %.0f) | width h/2 below "
              "the surface (mean): %.1f (h = 8 um), %.1f (h = 4 um)" % (
                  c["name"], c["P"], c["absorptivity"], c["width"] * 1e6,
                  c["depth"] * 1e6, out[0], k_mean, cp_mean, out[1],
                  m["k"](Ts), m["cp"](Ts), rows[0] * 1e6, rows[1] * 1e6))


def conduction_3d(c, h, props="file", eta=None, evap=False):
    """An independent reference for femp's heat conduction on case @p c:
    a cell-centred finite-volume solution (numpy, explicit in time) of
    rho dH/dt = div(k grad T) with the enthalpy H(T) = rho (int c dT + L f_l)
    and Kirchhoff fluxes (the difference of int k dT between neighbours,
    exact for k(T) in 1D), the Gaussian beam (1/e^2 radius r_b, absorbed
    power eta P, eta the measured absorptivity unless given) integrated exactly over
    each top cell's face, moving over the plate of the scene (same start,
    path and margins), half the plate (y >= 0, symmetry), no flow, no
    surface losses. @p props: 'file' (the alloy's tables and latent heat),
    'nolatent' (L = 0), 'const' (k, c_p averaged over T0..T_s, L = 0: the
    Eagar-Tsai setting). Returns the fusion width read on the top row of
    cells (h/2 below the surface) and at the surface (extrapolated from the
    two top rows), and the depth, from the peak temperature of each cell,
    median over sections at 40-70 % of the path; and the hottest top-row
    cell and extrapolated surface temperatures over those sections.
    @p evap: the top face loses the Hertz-Knudsen-Langmuir evaporation
    flux of femp's default (zeta_q = 0.82, the material file's L_v, M and
    T_v, p_0 = 101325 Pa; explicit in time)."""
    import numpy as np
    m = material(c["alloy"])
    rho, Ts, Tl, T0 = m["rho"], m["Ts"], m["Tl"], c["T0"]
    eta = eta or c["absorptivity"]
    P, rb, v = c["P"], c["rb"], c["v"]
    Tm = [T0 + (Ts - T0) * (i + 0.5) / 100 for i in range(100)]
    k_mean = sum(m["k"](T) for T in Tm) / 100
    cp_mean = sum(m["cp"](T) for T in Tm) / 100
    Tg = np.linspace(200.0, 6000.0, 58001)
    if props == "const":
        kg, cg, L = np.full_like(Tg, k_mean), np.full_like(Tg, cp_mean), 0.0
    else:
        kg = np.array([m["k"](T) for T in Tg])
        cg = np.array([m["cp"](T) for T in Tg])
        L = 0.0 if props == "nolatent" else m["L"]
    cum = lambda f: np.concatenate([[0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(Tg))])
    Hg = rho * (cum(cg) + L * np.clip((Tg - Ts) / (Tl - Ts), 0, 1))
    Kg = cum(kg)                                     # Kirchhoff potential
    x0, Ltr = MARGIN_START, track_geometry(c)["Ltr"]
    nx = int(round((x0 + Ltr + MARGIN_END) / h))
    ny, nz = int(round(2 * c["width"] / h)), int(round(max(120e-6, 4 * c["depth"]) / h))
    T = np.full((nx, ny, nz), T0)                    # [x, y, z], z = 0 the top row
    H = np.interp(T, Tg, Hg)
    dt = 0.9 * rho * cg.min() * h * h / (6 * kg.max())
    nsteps = int(math.ceil(Ltr / v / dt))
    dt = Ltr / v / nsteps
    s = rb / 2 * math.sqrt(2)                        # exp(-2 r^2/rb^2) = exp(-r^2/s^2)
    erf = np.vectorize(math.erf)
    yf, xf = np.arange(ny + 1) * h, np.arange(nx + 1) * h
    gy = 0.5 * np.diff(erf(yf / s))                  # sums to 1/2: half the beam
    K0 = float(np.interp(T0, Tg, Kg))
    Tpk = T.copy()
    for n in range(nsteps):
        xb = x0 + v * (n + 0.5) * dt
        gx = 0.5 * np.diff(erf((xf - xb) / s))
        K = np.interp(T, Tg, Kg)
        div = np.zeros_like(T)
        for ax in range(3):
            f = np.diff(K, axis=ax) / h
            lo = [slice(None)] * 3
            hi = [slice(None)] * 3
            lo[ax], hi[ax] = slice(0, -1), slice(1, None)
            div[tuple(lo)] += f
            div[tuple(hi)] -= f
        div[:, :, -1] += (K0 - K[:, :, -1]) / (0.5 * h)   # bottom at T0
        H += dt * div / h
        H[:, :, 0] += dt * eta * P * np.outer(gx, gy) / h ** 3
        if evap:
            Tt = T[:, :, 0]
            H[:, :, 0] -= dt / h * 0.82 * m["Lv"] * m["M"] / np.sqrt(
                2 * math.pi * m["M"] * 8.314462618 * Tt) * 101325.0 * np.exp(
                m["Lv"] * m["M"] / 8.314462618 * (Tt - m["Tv"]) / (Tt * m["Tv"]))
        T = np.interp(H, Hg, Tg)
        np.maximum(Tpk, T, out=Tpk)

    def edge(prof):
        hot = np.nonzero(prof >= Ts)[0]
        if len(hot) == 0:
            return 0.0
        j = hot[-1]
        if j + 1 >= len(prof):
            return (j + 1) * h
        return (j + 0.5) * h + h * (prof[j] - Ts) / (prof[j] - prof[j + 1])
    sec = range(int((x0 + 0.4 * Ltr) / h), int((x0 + 0.7 * Ltr) / h))
    surf = 1.5 * Tpk[:, :, 0] - 0.5 * Tpk[:, :, 1]
    med = lambda a: float(np.median(a))
    return dict(width_top_row=med([2 * edge(Tpk[i, :, 0]) for i in sec]),
                width_surface=med([2 * edge(surf[i]) for i in sec]),
                depth=med([edge(Tpk[i, 0, :]) for i in sec]),
                T_top=float(Tpk[sec.start:sec.stop, :, 0].max()),
                T_surface=float(surf[sec.start:sec.stop].max()),
                cells=nx * ny * nz, steps=nsteps)


def cmd_conduction3d(args):
    """The reference conduction solution (conduction_3d) of the cases."""
    rx = re.compile(args.cases or r"^trapp_032W$")
    for c in cases():
        if not rx.search(c["name"]) or not c.get("absorptivity"):
            continue
        for props in (args.props or "file,nolatent,const").split(","):
            for h in (float(x) * 1e-6 for x in (args.h or "8,4").split(",")):
                r = conduction_3d(c, h, props, args.eta, args.evap)
                print("%-12s %-9s h %4.1f um: width top row %5.1f um, at the "
                      "surface %5.1f um, depth %5.1f um (measured %5.1f / %5.1f; "
                      "%d cells, %d steps); hottest top-row cell %.0f K, "
                      "surface %.0f K%s" % (
                          c["name"], props, h * 1e6, r["width_top_row"] * 1e6,
                          r["width_surface"] * 1e6, r["depth"] * 1e6,
                          c["width"] * 1e6, c["depth"] * 1e6, r["cells"], r["steps"],
                          r["T_top"], r["T_surface"],
                          ", with evaporative cooling" if args.evap else ""),
                      flush=True)


def spot_onsets(out):
    """Melt and keyhole onset of a stationary-spot run from its time
    series: the first time the hottest cell reaches the solidus, and the
    times the absorbed fraction (absorption.csv) first reaches 0.35, 0.45
    and 0.6 (the flat surface absorbs the Fresnel value, about 0.3 for
    316L; the rise is the depression's multiple reflections)."""
    run = femp_post.Run(out)
    a = {k: v.tolist() for k, v in run.absorption().items()}
    m = {k: v.tolist() for k, v in run.melt_pool().items()}
    Ts = material("316L")["Ts"]
    r = {"t_melt": next((t for t, T in zip(m["time"], m["T_max"])
                         if T >= Ts), None),
         "t_end": a["time"][-1],
         "absorbed_end": a["absorbed_fraction"][-1],
         "hits_end": a["hits_per_ray"][-1],
         "depth_end": m["depth"][-1]}
    for th in (0.35, 0.45, 0.6):
        r["t_%.2f" % th] = next((t for t, f in zip(a["time"],
                                                    a["absorbed_fraction"])
                                 if f >= th), None)
    return r


def cmd_spots(args):
    """Simonds' stationary spots, the first part of the pulse on a plate
    cut to 0.64 x 0.64 x 0.304 mm (the rays reach 2 r_b = 303 um from the
    axis), 8 um cells, 19 rays per beam radius (8 um apart): the melt and
    keyhole onset against the measured ones."""
    exe = os.path.abspath(os.path.join(args.build, "femp"))
    rx = re.compile(args.cases or r"^simonds_(626|463|378)W$")
    for c in cases():
        if c["v"] != 0 or not rx.search(c["name"]):
            continue
        d = os.path.join(args.out, "spots", c["name"])
        out = os.path.join(d, "output")
        if not os.path.exists(os.path.join(out, "absorption.csv")):
            os.makedirs(d, exist_ok=True)
            scene = os.path.join(d, "scene.prm")
            open(scene, "w").write(spot_scene_text(c).replace(
                "include ../materials/", "include %s/prm/materials/" % ROOT))
            t_end = args.end_time or max(4e-4, 1.5e-3 * (c.get("t_keyhole_ms") or 0))
            sets = {"Background grid/Upper corner": "0.00064, 0.00064, 0.000352",
                    "Material points/Substrate top": "0.000304",
                    "Laser/Start point": "0.000315, 0.00032, 0",
                    "Laser/End point": "0.000325, 0.00032, 0",
                    "Laser/Rays per beam radius": "19",
                    "Time stepping/End time": fmt(t_end),
                    "Output/Time series interval": "5e-06",
                    "Output/Directory": out}
            print("run %s to %.2f ms ..." % (c["name"], t_end * 1e3), flush=True)
            rc, wall, cpu = run_timed(femp_cmd(args, exe, sets, scene), d,
                                      os.path.join(d, "log.txt"), args.max_wall)
            print("  rc %s, %.0f s wall x %d ranks, %.0f CPU s" % (
                rc, wall, args.np, cpu), flush=True)
        r = spot_onsets(out)
        f = lambda t: ("%.3f" % (t * 1e3)) if t else "-"
        ms = lambda t: ("%.3f" % t) if t else "-"
        print("%-14s melt onset %s ms (measured %s); absorbed >= 0.35 / 0.45 / "
              "0.6 at %s / %s / %s ms (keyhole onset measured %s ms); at %.2f ms "
              "absorbed %.3f, %.2f hits per ray, pool depth %.0f um" % (
                  c["name"], f(r["t_melt"]), ms(c.get("t_melt_ms")), f(r["t_0.35"]),
                  f(r["t_0.45"]), f(r["t_0.60"]), ms(c.get("t_keyhole_ms")),
                  r["t_end"] * 1e3, r["absorbed_end"], r["hits_end"],
                  r["depth_end"] * 1e6), flush=True)
    spots_figure(args.out, args.img)


def spots_figure(out, img):
    """The absorbed fraction against time of every finished spot run under
    out/spots, with the measured keyhole onsets (on the flat-surface
    value's level, 0.3) for comparison."""
    colours = ["#c92a2a", "#e67700", "#2b8a3e", "#1f5fbf", "#862e9c"]
    allc = {c["name"]: c for c in cases()}
    series, onsets = [], []
    d = os.path.join(out, "spots")
    names = sorted((n for n in (os.listdir(d) if os.path.isdir(d) else [])
                    if n in allc and os.path.exists(
                        os.path.join(d, n, "output", "absorption.csv"))),
                   key=lambda n: -allc[n]["P"])
    for k, n in enumerate(names):
        a = femp_post.Run(os.path.join(d, n, "output")).absorption()
        series.append(("femp, %s" % allc[n]["label"], colours[k % len(colours)],
                       [(t * 1e3, f, 0, 0, "") for t, f in
                        list(zip(a["time"].tolist(),
                                 a["absorbed_fraction"].tolist()))[::4]]))
        if allc[n].get("t_keyhole_ms"):
            onsets.append((allc[n]["t_keyhole_ms"], 0.3, 0, 0, allc[n]["label"]))
    if not series:
        return
    series.append(("measured keyhole onset", "#000000", onsets))
    os.makedirs(img, exist_ok=True)
    svg_scatter(os.path.join(img, "validation_simonds_absorption.svg"), series,
                "Stationary spots (Simonds 2018, 316L): absorbed fraction",
                "time (ms)", "absorbed fraction", diag=False, ylim=(0, 1),
                pad=False, lines=tuple(sr[0] for sr in series[:-1]))


def cmd_scenes(args):
    os.makedirs(SCENES, exist_ok=True)
    bad = []
    for c in cases():
        f = os.path.join(SCENES, c["name"] + ".prm")
        text = scene_text(c)
        if args.check:
            if not os.path.exists(f) or open(f).read() != text:
                bad.append(f)
            continue
        with open(f, "w") as fh:
            fh.write(text)
    if bad:
        raise SystemExit("validate.py: scenes out of date (run contrib/validate.py "
                         "scenes): " + ", ".join(bad))
    print("%d scenes %s" % (len(cases()), "up to date" if args.check else
                            "written to " + SCENES))


# ---------------------------------------------------------------- runs
def process_cpu(pid):
    """CPU seconds (user + system) used so far by process pid and its
    descendants (the ranks under mpirun), from /proc; 0 where unreadable."""
    tick = os.sysconf("SC_CLK_TCK")
    parent, used = {}, {}
    for e in os.listdir("/proc"):
        if not e.isdigit():
            continue
        try:
            f = open("/proc/%s/stat" % e).read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        parent[int(e)] = int(f[1])
        used[int(e)] = (int(f[11]) + int(f[12])) / tick
    total, todo = 0.0, [pid]
    while todo:
        p = todo.pop()
        total += used.get(p, 0.0)
        todo += [c for c, pp in parent.items() if pp == p]
    return total


def run_timed(cmd, cwd, log, max_wall=None, append=False, stop=None,
              progress=None):
    """Run cmd in cwd, stdout+stderr to log (appended to with @p append);
    (exit code, wall s, CPU s of the run and its children). After max_wall
    seconds, or when stop() returns true (polled), the run is stopped
    (exit code -15) and what it wrote is kept. progress(wall, cpu) is
    called every PROGRESS_S seconds while the run goes on. A SIGTERM to
    this script stops the run too (and is raised again after)."""
    import signal
    t0 = time.time()
    term = []
    old = signal.signal(signal.SIGTERM, lambda *a: term.append(1))
    try:
        with open(log, "a" if append else "w") as out:
            p = subprocess.Popen(cmd, cwd=cwd, stdout=out,
                                 stderr=subprocess.STDOUT)
            t_progress = t0
            while True:
                pid, status, ru = os.wait4(p.pid, os.WNOHANG)
                if pid:
                    break
                if (term or (max_wall and time.time() - t0 > max_wall)
                        or (stop and stop())):
                    cpu = process_cpu(p.pid)
                    p.terminate()
                    pid, status, ru = os.wait4(p.pid, 0)
                    break
                if progress and time.time() - t_progress > PROGRESS_S:
                    t_progress = time.time()
                    progress(t_progress - t0, process_cpu(p.pid))
                time.sleep(0.2)
    finally:
        signal.signal(signal.SIGTERM, old)
    result = (os.waitstatus_to_exitcode(status), time.time() - t0,
              ru.ru_utime + ru.ru_stime)
    if term:
        if progress:
            progress(result[1], max(result[2], cpu))
        raise Stopped(result[0])
    return result


PROGRESS_S = 60


class Stopped(SystemExit):
    """This script got a SIGTERM while a run went on; the run was stopped
    (its exit code: rc)."""

    def __init__(self, rc):
        SystemExit.__init__(self, "validate.py: stopped by SIGTERM")
        self.rc = rc


def window_stats(table, key, t0, t1):
    """Median and largest value of a column over t0 <= time <= t1."""
    v = sorted(x for t, x in zip(table["time"].tolist(), table[key].tolist())
               if t0 <= t <= t1)
    if not v:
        return None, None
    n = len(v)
    med = v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])
    return med, v[-1]


def time_mean(table, key, t0, t1):
    """Time mean (trapezoids) of a column over t0 <= time <= t1."""
    pts = [(t, x) for t, x in zip(table["time"].tolist(), table[key].tolist())
           if t0 <= t <= t1]
    if len(pts) < 2:
        return pts[0][1] if pts else None
    s = sum(0.5 * (a[1] + b[1]) * (b[0] - a[0]) for a, b in zip(pts, pts[1:]))
    return s / (pts[-1][0] - pts[0][0])


def log_figures(text):
    """Figures of a femp run's printed report (log.txt), by
    femp_post.read_printed: the last step number, fluid steps, energies,
    the absorbed fraction, the scene's normalized enthalpy, the wall time."""
    lines = text.split("\n")

    def printed(pattern):
        return femp_post.read_printed(lines, pattern)

    r = {}
    m = printed(r"Melt flow: ([0-9]+) fluid steps")
    r["fluid_steps"] = int(m["1"][0]) if len(m) else None
    m = printed(r"step +([0-9]+) +dt =")
    r["steps"] = int(m["1"][-1]) if len(m) else None
    m = printed(r"Energy \(J\): laser ([-0-9.e+]+), surface losses "
                r"([-0-9.e+]+) \(evaporation ([-0-9.e+]+)")
    if len(m):
        r.update(laser_J=float(m["1"][0]), losses_J=float(m["2"][0]),
                 evaporation_J=float(m["3"][0]))
    # the ray-traced laser's account; its fraction is kept only where the
    # account closes (absorbed + escaping = incident to round-off)
    m = printed(r"incident ([-0-9.e+]+), absorbed ([-0-9.e+]+) \(fraction "
                r"([-0-9.e+]+)\), escaping ([-0-9.e+]+); relative error "
                r"[^0-9]*([-0-9.e+]+)")
    if len(m) and float(m["5"][0]) < 1e-9:
        r["absorbed_fraction_run"] = float(m["3"][0])
    m = printed(r"normalized enthalpy [^=]*= ([0-9.e+]+)")
    r["normalized_enthalpy"] = float(m["1"][0]) if len(m) else None
    m = printed(r"[Ww]all (?:time|clock)[^0-9]*([0-9.]+) *s")
    r["femp_wall_s"] = float(m["1"][0]) if len(m) else None
    return r


def evaluate(out_dir, t_end, log_text=""):
    """The fusion zone and absorbed fraction of a finished run."""
    r = log_figures(log_text)
    run = femp_post.Run(out_dir)
    pool = run.melt_pool()
    t_last = max(pool["time"].tolist())
    r["t_reached"] = t_last
    # a run stopped early (wall-time cap): the same window of the path it
    # reached, marked incomplete by the caller
    t_end = min(t_end, t_last)
    t0, t1 = 0.6 * t_end, t_end * (1 + 1e-9)
    for key, name in (("width_solidus_substrate", "width"),
                      ("depth_solidus_substrate", "depth"),
                      ("T_max", "T_max"), ("length", "length")):
        med, mx = window_stats(pool, key, t0, t1)
        r[name], r[name + "_max"] = med, mx
    # steadiness: median of the last 20 % against the 20 % before
    a, _ = window_stats(pool, "depth_solidus_substrate", 0.6 * t_end, 0.8 * t_end)
    b, _ = window_stats(pool, "depth_solidus_substrate", 0.8 * t_end, t1)
    r["depth_growth"] = (b / a - 1) if a and b else None
    f = os.path.join(out_dir, "absorption.csv")
    if os.path.exists(f):
        ab = run.absorption()
        r["absorbed"] = time_mean(ab, "absorbed_fraction", t0, t1)
        r["hits_per_ray"] = time_mean(ab, "hits_per_ray", t0, t1)
    return r


EVAPORATION = {"IN718": (6.43e6, 0.0580, 3186.0), "316L": (7.41e6, 0.0558, 3090.0)}


def scene_value(scene, key):
    m = re.search(r"set %s\s*=\s*([^#\n]*)" % re.escape(key), scene)
    return [float(v) for v in m.group(1).split(",")] if m else None


def end_state(run_dir, alloy):
    """What digs the pool, from the last field output of a run: the
    depression depth under and behind the beam (the lowest metal surface
    within 4 r_b behind to 1 r_b ahead of the beam axis, the centre column
    and its two neighbours across), the surface temperature there and the
    recoil pressure zeta_p p_sat(T) it gives (Clausius-Clapeyron with the
    alloy's evaporation data, as femp computes it), the fastest melt."""
    out = os.path.join(run_dir, "output")
    try:
        g = femp_post.Run(out).grid()
    except (OSError, ValueError, KeyError, IndexError):
        return {}
    names = list(g.keys())
    cells = {tuple(float(x) for x in c): {k: float(g[k][i]) for k in names}
             for i, c in enumerate(g.centres)}
    scene = open(os.path.join(run_dir, "scene.prm")).read()
    h = scene_value(scene, "Cell size")[0]
    ztop = scene_value(scene, "Substrate top")[0]
    rb = scene_value(scene, "Beam radius")[0]
    xb, yc, _ = scene_value(scene, "End point")
    cols = {}
    for (x, y, z), f in cells.items():
        if abs(y - yc) <= 1.01 * h and xb - 4 * rb <= x <= xb + rb:
            cols.setdefault((x, y), []).append((z, f))
    surf = {}
    for key, col in cols.items():
        col.sort(key=lambda t: -t[0])
        for z, f in col:
            if f["alpha"] >= 0.5:
                surf[key] = (z + h * (f["alpha"] - 0.5), f["T"])
                break
    r = {}
    if surf:
        Lv, M, Tv = EVAPORATION[alloy]
        recoil = lambda T: 0.54 * 101325 * math.exp(
            Lv * M * (T - Tv) / (8.314462618 * T * Tv))
        deepest = min(surf.values())
        r["depression"] = max(0.0, ztop - deepest[0])
        # the column on the beam axis (nearest cell centre)
        axis = min(surf, key=lambda k: (abs(k[0] - xb), abs(k[1] - yc)))
        r["depression_axis"] = max(0.0, ztop - surf[axis][0])
        r["T_axis"] = surf[axis][1]
        r["recoil_axis"] = recoil(surf[axis][1])
        hottest = max(surf.values(), key=lambda t: t[1])
        r["T_surface_max"] = hottest[1]
        r["recoil_max"] = recoil(hottest[1])
    speeds = [math.sqrt(f["u_x"] ** 2 + f["u_y"] ** 2 + f["u_z"] ** 2)
              for f in cells.values() if f.get("alpha", 0) >= 0.5 and "u_x" in f]
    r["u_max"] = max(speeds) if speeds else None
    return r


def cell_size(scene, log):
    """The background grid's cell size: femp's log line, else the scene's
    'Cell size'."""
    m = re.search(r"background grid: [0-9]+ cells of ([0-9.e+-]+) m", log)
    return float(m.group(1)) if m else scene_value(scene, "Cell size")[0]


def cell_arrays(g, h, names):
    """The cell fields @p names of one field output @p g on the structured
    grid of cell size @p h, as arrays indexed [x, y, z]: T is NaN and the
    other fields 0 where the output holds no cell."""
    import numpy as np
    ijk = np.floor(np.asarray(g.centres) / h).astype(int)
    n = ijk.max(axis=0) + 1
    out = []
    for name in names:
        a = np.full(n, np.nan) if name == "T" else np.zeros(n)
        if name in g:
            a[tuple(ijk.T)] = g[name]
        out.append(a)
    return out


def width_state(run_dir, alloy):
    """What sets the fusion zone's width, from the last field output of a
    run: the cross-section (y-z plane of cells; from 'Output/Melt pool from
    x' on, as melt_pool.csv measures) where the region above the
    solidus in the substrate is widest, its distance behind the beam, the
    temperature of the top substrate cells on the track axis there, and
    the sense of the melt's surface flow across the track: the mean of
    u_y sign(y - y_axis) over the molten free surface (the top metal cell
    of each column, above the solidus) and over its rim (the outermost such
    cell on each side of each x slab); negative is inward, towards the
    axis, as a positive d sigma / dT drives it. Needs numpy
    (contrib/femp_post)."""
    import numpy as np
    g = femp_post.Run(os.path.join(run_dir, "output")).grid()
    scene = open(os.path.join(run_dir, "scene.prm")).read()
    h = cell_size(scene, open(os.path.join(run_dir, "log.txt")).read())
    ztop = scene_value(scene, "Substrate top")[0]
    xb, yc, _ = scene_value(scene, "End point")
    Ts = material(alloy)["Ts"]
    T, A, U = cell_arrays(g, h, ("T", "alpha", "u_y"))
    n = T.shape
    kt = int(round(ztop / h)) - 1            # top substrate row
    y = (np.arange(n[1]) + 0.5) * h
    jc = int(np.argmin(abs(y - yc)))
    # width of the region above T_s in each x slab, at the top row
    hot = (T[:, :, kt] >= Ts) & (A[:, :, kt] > 0)
    # only the slabs that melt_pool.csv measures ('Output/Melt pool from x')
    x_from = scene_value(scene, "Melt pool from x")
    i0 = max(0, int(math.ceil(x_from[0] / h - 0.5 - 1e-9))) if x_from else 0
    hot[:i0] = False
    widths = hot.sum(axis=1) * h
    i_w = int(np.argmax(widths))
    i_b = int(min(n[0] - 1, max(0, round(xb / h - 0.5))))

    # the melt's free surface: the top metal cell of each column, molten
    top = np.where(A >= 0.5, np.arange(n[2])[None, None, :], -1).max(axis=2)
    ii, jj = np.nonzero(top >= 0)
    kk = top[ii, jj]
    molten = T[ii, jj, kk] >= Ts
    ii, jj, kk = ii[molten], jj[molten], kk[molten]
    side = np.sign(y[jj] - yc)
    across = U[ii, jj, kk] * side          # > 0: outward, away from the axis
    off = side != 0
    # the rim: the outermost molten surface cell on each side of each slab
    rim = np.zeros(len(ii), bool)
    for i in np.unique(ii):
        for sg in (-1, 1):
            sel = np.nonzero((ii == i) & (side == sg))[0]
            if len(sel):
                rim[sel[np.argmax(abs(y[jj[sel]] - yc))]] = True
    mean = lambda m: float(across[m].mean()) if m.any() else None
    return dict(x_behind_beam=xb - (i_w + 0.5) * h, width_cells=float(widths[i_w]),
                T_axis_top=float(T[i_w, jc, kt]),
                flow_across_surface=mean(off), flow_across_rim=mean(rim & off),
                **fusion_width_rows(T[i0:], A[i0:], kt, h, Ts))


def fusion_width_rows(T, A, kt, h, Ts):
    """The widest fusion width of the last field output (cells T, metal
    fraction A indexed [x, y, z], top substrate row kt) read two ways: on
    the top substrate row, h/2 below the original surface
    ('width_top_row'), and at the original surface, the temperature
    extrapolated linearly from the two top rows (1.5 T_kt - 0.5 T_kt-1;
    'width_surface', as femp's melt_pool.csv reads it); the crossing of T_s
    interpolated linearly between cell centres in both. Where the pool's
    edge lies under the beam the solidus meets the surface at an angle, and
    the width shrinks linearly with depth: the top-row reading is then short
    by an amount proportional to h."""
    import numpy as np

    def span(prof, ok):
        hot = np.nonzero(ok & (prof >= Ts))[0]
        if len(hot) == 0:
            return 0.0
        lo, hi = hot[0], hot[-1]
        xl = (lo + 0.5) * h
        if lo > 0 and ok[lo - 1]:
            xl -= h * (prof[lo] - Ts) / (prof[lo] - prof[lo - 1])
        xh = (hi + 0.5) * h
        if hi + 1 < len(prof) and ok[hi + 1]:
            xh += h * (prof[hi] - Ts) / (prof[hi] - prof[hi + 1])
        return xh - xl

    top, below = T[:, :, kt], T[:, :, kt - 1]
    ok = (A[:, :, kt] >= 0.5) & (A[:, :, kt - 1] >= 0.5) & np.isfinite(top)
    surf = 1.5 * top - 0.5 * below
    w_top = max(span(top[i], ok[i]) for i in range(T.shape[0]))
    w_surf = max(span(surf[i], ok[i]) for i in range(T.shape[0]))
    return dict(width_top_row=float(w_top), width_surface=float(w_surf))


def _neighbour(a, axis, side, fill):
    """a at the face neighbour on @p side (-1, +1) along @p axis; @p fill
    beyond the domain."""
    import numpy as np
    b = np.roll(a, -side, axis=axis)
    idx = [slice(None)] * a.ndim
    idx[axis] = -1 if side > 0 else 0
    b[tuple(idx)] = fill
    return b


def _grow(seed, may, axes):
    """seed grown through the cells where may holds, face neighbours along
    @p axes."""
    cur = seed & may
    while True:
        nxt = cur.copy()
        for ax in axes:
            for side in (-1, 1):
                nxt |= _neighbour(cur, ax, side, False)
        nxt &= may
        if (nxt == cur).all():
            return cur
        cur = nxt


def isotherm_y_extent(T, A, h, T_iso, z_top, x_min=-math.inf, why=None,
                      detached=False):
    """The y-extent (lo, hi) of femp's isotherm box (measure_melt_pool in
    source/heat/melt_pool.cc) on the cells of one field output, T and
    metal fraction A indexed [x, y, z]: the metal cells with centre below
    z_top at or above T_iso connected to colder metal, their crossings
    interpolated towards colder metal (the cell face towards gas), and the
    crossings at the surface, T extrapolated from the top counted cell and
    the one below to the surface height; the metal not face-connected to
    the domain's bottom row (detached drops: femp counts only the
    workpiece, attached_metal_cells in source/grid/metal_bodies.cc) and the
    cells with centre x < x_min are gas. With z_top the substrate top and
    T_iso = T_s it is melt_pool.csv's width_solidus_substrate. None: no
    pool. @p why, a
    dict, receives the branches of the box that set lo and hi ('lo', 'hi':
    sets of the pass, 'interior' or 'surface', and the crossing: 'cross'
    interpolated towards colder metal, 'gas' the face towards gas,
    'boundary' the domain's face, 'centre' the cell centre; every branch
    that reaches the extreme). @p detached: count the detached metal as
    femp does not (tests/isotherm_y_extent.py checks that its scene has
    some that would change the box)."""
    import numpy as np
    n = T.shape
    xc, zc = (np.arange(n[0]) + 0.5) * h, (np.arange(n[2]) + 0.5) * h
    y = ((np.arange(n[1]) + 0.5) * h)[None, :, None]
    A = np.where(np.isfinite(T), A, 0.0)
    bottom = np.zeros(n, bool)
    bottom[:, :, 0] = True
    workpiece = (A > 0) if detached else _grow(bottom, A > 0, range(3))
    metal = np.where((xc >= x_min)[:, None, None] & workpiece, A, 0.0)
    Tf = np.where(np.isfinite(T), T, 0.0)
    below = (zc < z_top)[None, None, :]
    melt = (metal > 0) & (Tf >= T_iso) & below
    cold = (metal > 0) & (Tf < T_iso)
    seed = np.zeros(n, bool)
    for ax in range(3):
        for side in (-1, 1):
            seed |= _neighbour(cold, ax, side, False)
    seed &= melt
    if seed.any():
        pool = _grow(seed, melt, range(3))
    elif not cold.any():
        pool = melt
    else:
        return None
    if not pool.any():
        return None
    ext = {"lo": (math.inf, set()), "hi": (-math.inf, set())}

    def extend(x, kind, cells):
        """Widen lo and hi to the extreme x over @p cells; kind: the
        branch of each cell's crossing (the branches of every cell at the
        extreme are kept)."""
        xs, ks = x[cells], kind[cells]
        for end, v in (("lo", xs.min()), ("hi", xs.max())):
            at = set(ks[xs == v].tolist())
            if v == ext[end][0]:
                ext[end][1].update(at)
            elif (v < ext[end][0]) == (end == "lo"):
                ext[end] = (v, at)

    names = np.array(["centre", "cross", "gas", "boundary"])
    for side in (-1, 1):
        Tn = _neighbour(Tf, 1, side, 0.0)
        mn = _neighbour(metal, 1, side, -1.0)       # -1: beyond the domain
        x = np.broadcast_to(y, n).copy()
        cross = (mn > 0) & (Tn < T_iso)
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.where(cross, x + side * h * (Tf - T_iso) / (Tf - Tn), x)
        x = np.where(mn <= 0, x + side * 0.5 * h, x)
        kind = names[np.where(cross, 1, np.where(mn < 0, 3,
                                                 np.where(mn <= 0, 2, 0)))]
        extend(x, np.char.add("interior ", kind), pool)
    counted = (metal > 0) & below
    top = counted & ~_neighbour(counted, 2, 1, False)
    zs = np.minimum(z_top, zc[None, None, :] + h * (np.minimum(metal, 1.0) - 0.5))
    dz = np.clip(zs - zc[None, None, :], -0.5 * h, 0.5 * h)
    has_below = _neighbour(counted, 2, -1, False)
    Ts = Tf + np.where(has_below, dz / h * (Tf - _neighbour(Tf, 2, -1, 0.0)), 0.0)
    Ts = np.where(top, Ts, -1.0)
    hot = Ts >= T_iso
    surf = _grow(pool & hot, hot, (0, 1))
    for side in (-1, 1):
        Tn = _neighbour(Ts, 1, side, -1.0)
        mn = _neighbour(metal, 1, side, -1.0)
        x = np.broadcast_to(y, n).copy()
        cross = (Tn >= 0) & (Tn < T_iso)
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.where(cross, x + side * h * (Ts - T_iso) / (Ts - Tn), x)
        face = ~cross & (Tn < 0) & (mn <= 0)
        x = np.where(face, x + side * 0.5 * h, x)
        kind = names[np.where(cross, 1, np.where(face & (mn < 0), 3,
                                                 np.where(face, 2, 0)))]
        if surf.any():
            extend(x, np.char.add("surface ", kind), surf)
    if why is not None:
        why.update(lo=ext["lo"][1], hi=ext["hi"][1])
    return float(ext["lo"][0]), float(ext["hi"][0])


def near_beam_width(run_dir, alloy, behind=96e-6):
    """The fusion width near the beam: melt_pool.csv's reading
    (width_solidus_substrate, isotherm_y_extent()) of each field output in
    the last 40 % of the laser's path with only the cells from x_beam -
    @p behind on (and from 'Output/Melt pool from x' on), x_beam = the
    start point + scan speed x time; beside it the same reading over the
    whole measured region, which melt_pool.csv's row of that time gives.
    Returns [(time, near, measured region)] and the median of near."""
    import numpy as np
    run = femp_post.Run(os.path.join(run_dir, "output"))
    scene = open(os.path.join(run_dir, "scene.prm")).read()
    h = cell_size(scene, open(os.path.join(run_dir, "log.txt")).read())
    ztop = scene_value(scene, "Substrate top")[0]
    x0, xe = scene_value(scene, "Start point")[0], scene_value(scene, "End point")[0]
    v = scene_value(scene, "Scan speed")[0]
    t_end = scene_value(scene, "End time")[0]
    x_from = (scene_value(scene, "Melt pool from x") or [-math.inf])[0]
    Ts = material(alloy)["Ts"]
    if xe < x0:
        raise ValueError("the near-beam reading takes tracks along +x")
    rows = []
    for n_out, t in run.outputs():
        if t < 0.6 * t_end:
            continue
        T, A = cell_arrays(run.grid(n_out), h, ("T", "alpha"))
        xb = min(x0 + v * t, xe)
        w = []
        for xm in (max(x_from, xb - behind), x_from):
            b = isotherm_y_extent(T, A, h, Ts, ztop, xm)
            w.append(b[1] - b[0] if b else 0.0)
        rows.append((t, w[0], w[1]))
    med = float(np.median([r[1] for r in rows])) if rows else None
    return rows, med


def cmd_width(args):
    """The width diagnostics of every finished run under --out."""
    allc = {c["name"]: c for c in cases()}
    print("%-9s %-12s %8s %8s %10s %10s %12s %12s %10s %10s %10s" % (
        "setting", "case", "width", "measured", "behind(um)", "T_axis(K)",
        "u_surface", "u_rim", "end:row", "end:surf", "near96"))
    for (setting, name), r in sorted(load_results(args.out).items()):
        if not re.search(args.cases or ".", name) or r.get("incomplete"):
            continue
        try:
            w = width_state(os.path.join(args.out, setting, name),
                            allc[name]["alloy"])
        except (OSError, ValueError, KeyError, IndexError) as ex:
            print(setting, name, "no field output:", ex)
            continue
        f = lambda v: ("%+.2f" % v) if v is not None else "-"
        try:
            rows, near = near_beam_width(os.path.join(args.out, setting, name),
                                         allc[name]["alloy"])
        except ValueError:
            rows, near = [], None
        print("%-9s %-12s %8.1f %8.1f %10.1f %10.0f %12s %12s %10.1f %10.1f %10s" % (
            setting, name, r["width"] * 1e6, allc[name]["width"] * 1e6,
            w["x_behind_beam"] * 1e6, w["T_axis_top"],
            f(w["flow_across_surface"]), f(w["flow_across_rim"]),
            w["width_top_row"] * 1e6, w["width_surface"] * 1e6,
            ("%.1f (%d)" % (near * 1e6, len(rows))) if near is not None else "-"))


def femp_cmd(args, exe, sets, scene):
    cmd = (["mpirun", "--allow-run-as-root", "--oversubscribe", "-np",
            str(args.np), exe] if args.np > 1 else [exe])
    for k, v in sets.items():
        cmd += ["--set", "%s=%s" % (k, v)]
    return cmd + [scene]


def last_time(out_dir):
    """The last time of a run's melt_pool.csv (None if it has no row)."""
    try:
        t = femp_post.Run(out_dir).melt_pool()["time"].tolist()
    except (OSError, ValueError, KeyError, IndexError):
        return None
    return max(t) if t else None


def checkpoints(d):
    """The checkpoints of run directory d that femp's index names (newest
    first; femp keeps the last two of the triggers, and a rebalance's only
    while it is the newest, doc/checkpoint.md)."""
    try:
        return [x.strip() for x in open(os.path.join(d, CHECKPOINT_DIR, "index"))
                if x.strip()]
    except OSError:
        return []


def segment_controls(k):
    """Parameters that steer a segment (where and when femp checkpoints,
    where it resumes), not the run's physics: they may differ between the
    segments of one run and are not part of its 'sets'."""
    return k == "Output/Directory" or k.startswith("Checkpoint/")


CHECKPOINT_DIR = "checkpoint"


def run_case(args, exe, c, setting, stop=None):
    """Run case c with setting in <out>/<setting>/<name> and evaluate it
    into result.json; a directory with result.json is skipped. With
    checkpoints (--checkpoint-minutes, or any 'Checkpoint/Every ...' by
    --set) femp writes them into <run>/checkpoint; a segment that stops
    before the end (--max-wall, a kill, stop() returning true) leaves no
    result.json, and the next call resumes from the latest checkpoint
    (segments.json: one record per segment; log.txt: all segments)."""
    d = os.path.join(args.out, setting, c["name"])
    f = os.path.join(d, "result.json")
    if os.path.exists(f):
        return json.load(open(f))
    os.makedirs(d, exist_ok=True)
    scene = os.path.join(d, "scene.prm")
    scale = 1.5 if "large" in setting.split("+") else 1.0
    text = scene_text(c, scale, is_compact(setting),
                      track_length(setting)).replace(
        "include ../materials/", "include %s/prm/materials/" % ROOT)
    sets = {"Output/Directory": os.path.join(d, "output")}
    sets.update(setting_parameters(setting))
    for kv in args.set or []:
        k, v = kv.split("=", 1)
        sets[k] = v
    if args.checkpoint_minutes:
        sets["Checkpoint/Every wall minutes"] = fmt(args.checkpoint_minutes)
    ckpt = os.path.join(d, CHECKPOINT_DIR)
    if any(k.startswith("Checkpoint/Every") and float(v) > 0
           for k, v in sets.items()):
        sets["Checkpoint/Directory"] = ckpt
    physics = {k: v for k, v in sets.items() if not segment_controls(k)}
    seg_file = os.path.join(d, "segments.json")
    segments = json.load(open(seg_file)) if os.path.exists(seg_file) else []
    resume = checkpoints(d)
    if resume:
        # the checkpoint must be of this run: same scene, same parameters
        same = (os.path.exists(scene) and open(scene).read() == text and
                segments and segments[0].get("sets") == physics)
        if not same:
            raise SystemExit(
                "validate.py: %s holds a checkpoint of a run with another scene "
                "or other parameters (segments.json: %s; now: %s); run it with "
                "the same --setting and --set, or remove the directory to start "
                "anew" % (d, segments[0].get("sets") if segments else "missing",
                          physics))
        sets["Checkpoint/Resume from"] = ckpt
        for g in segments:
            if g.get("ended") == "running":
                g["ended"] = "killed (wall and CPU up to its last record)"
    else:
        segments = []
        open(scene, "w").write(text)
    cmd = femp_cmd(args, exe, sets, scene)
    n = len(segments) + 1
    log = os.path.join(d, "log.txt")
    seg = dict(segment=n, started=time.strftime("%Y-%m-%d %H:%M:%S UTC",
                                                time.gmtime()),
               resumed_from=(os.path.join(CHECKPOINT_DIR, resume[0])
                             if resume else None),
               wall_s=0.0, cpu_s=0.0, rc=None, ended="running")
    if n == 1:
        seg["sets"] = physics
    segments.append(seg)

    def record(wall, cpu):
        seg.update(wall_s=wall, cpu_s=cpu, t_reached=last_time(
            os.path.join(d, "output")), checkpoints=checkpoints(d))
        json.dump(segments, open(seg_file, "w"), indent=1)

    record(0.0, 0.0)
    if resume:
        with open(log, "a") as out:
            out.write("\n# validate.py: segment %d, %s, resumed from %s\n" % (
                n, seg["started"], seg["resumed_from"]))
    print("run %s [%s]%s ..." % (c["name"], setting,
                                 (" segment %d, from %s" % (n, resume[0]))
                                 if resume else ""), flush=True)
    t_end = path_time(c, setting)
    log_start = os.path.getsize(log) if resume else 0
    seen = checkpoints(d)[:1]
    renew = []

    def segment_stop():
        """stop(), or with --restart-after-checkpoint a new checkpoint
        before the end (its time from femp's line in this segment's log)."""
        if stop and stop():
            return True
        now = checkpoints(d)[:1]
        if not getattr(args, "restart_after_checkpoint", False) or now == seen:
            return False
        # femp names a checkpoint in its index before its log line says
        # it: until that line is there, look again at the next poll.
        with open(log) as f:
            f.seek(log_start)
            m = re.findall(r"^Checkpoint: step ([0-9]+), time ([-0-9.e+]+) s",
                           f.read(), re.M)
        m = [t for step, t in m if now[0] == "step_%08d" % int(step)]
        if not m:
            return False
        seen[:] = now
        if float(m[-1]) < t_end * (1 - END_RTOL):
            renew.append(now[0])
            return True
        return False

    try:
        rc, wall, cpu = run_timed(cmd, d, log, args.max_wall,
                                  append=bool(resume), stop=segment_stop,
                                  progress=record)
    except Stopped as ex:
        seg.update(rc=ex.rc, ended="stopped by SIGTERM")
        json.dump(segments, open(seg_file, "w"), indent=1)
        raise
    seg.update(rc=rc)
    record(wall, cpu)
    reached = (seg.get("t_reached") or 0) >= t_end * (1 - END_RTOL)
    seg["ended"] = ("finished" if reached else
                    "stopped after checkpoint %s" % renew[0] if renew else
                    "stopped")
    json.dump(segments, open(seg_file, "w"), indent=1)
    if renew and not reached:
        # a fresh process goes on from the checkpoint just written
        return run_case(args, exe, c, setting, stop)
    if not reached and checkpoints(d):
        print("  segment %d stopped (rc %s) at t = %s s after %.0f s wall; "
              "the same command resumes from %s" % (
                  n, rc, seg.get("t_reached"), wall, checkpoints(d)[0]),
              flush=True)
        return None
    r = dict(name=c["name"], setting=setting, rc=rc,
             wall_s=sum(g["wall_s"] for g in segments),
             np=args.np, cpu_s=sum(g["cpu_s"] for g in segments),
             sets=physics)
    try:
        r.update(evaluate(os.path.join(d, "output"), t_end, open(log).read()))
    except (OSError, ValueError, KeyError) as ex:
        r["read_error"] = str(ex)
    if len(segments) > 1:
        # femp's printed wall time is the last segment's; wall_s is the sum
        r["segments"] = len(segments)
        r.pop("femp_wall_s", None)
    if r.get("t_reached", 0) >= t_end * (1 - END_RTOL):
        try:
            r.update(end_state(d, c["alloy"]))
        except (OSError, ValueError, KeyError, TypeError) as ex:
            r["end_state_error"] = str(ex)
    else:
        r["incomplete"] = True
    json.dump(r, open(f, "w"), indent=1)
    print("  rc %s, %.0f s wall, width %s um, depth %s um, absorbed %s" % (
        rc, r["wall_s"], um(r.get("width")), um(r.get("depth")),
        ("%.3f" % r["absorbed"]) if r.get("absorbed") is not None else "-"),
        flush=True)
    return r


def um(x):
    return "%.1f" % (x * 1e6) if x is not None else "-"


def cmd_reevaluate(args):
    """Evaluate every finished run again (after a change of the evaluation;
    nothing is rerun)."""
    allc = {c["name"]: c for c in cases()}
    for (setting, name), r in load_results(args.out).items():
        d = os.path.join(args.out, setting, name)
        t_end = path_time(allc[name], setting)
        r.update(evaluate(os.path.join(d, "output"), t_end,
                          open(os.path.join(d, "log.txt")).read()))
        if r["t_reached"] >= t_end * (1 - END_RTOL):
            r.pop("incomplete", None)
            r.update(end_state(d, allc[name]["alloy"]))
        else:
            r["incomplete"] = True
        json.dump(r, open(os.path.join(d, "result.json"), "w"), indent=1)
        print("re-evaluated", setting, name)


def cmd_run(args):
    exe = os.path.abspath(os.path.join(args.build, "femp"))
    if not os.path.exists(exe):
        raise SystemExit("validate.py: build femp first (%s)" % exe)
    rx = re.compile(args.cases or DEFAULT_CASES)
    todo = [c for c in cases() if rx.search(c["name"]) and c["v"] > 0]
    for c in todo:
        run_case(args, exe, c, args.setting)


RESUME_KEYS = ("t_reached", "width", "width_max", "depth", "depth_max",
               "T_max", "length", "absorbed", "hits_per_ray", "steps",
               "fluid_steps", "laser_J", "losses_J", "evaporation_J",
               "absorbed_fraction_run", "u_max", "depression")
RESUME_FILES = ("melt_pool.csv", "absorption.csv", "track_bead.csv")


def cmd_resume_check(args):
    """A run in segments gives the numbers of a run straight through: the
    case (default Trapp 32 W, 8 um) run three times under --out: 'straight'
    without checkpoints; 'checkpointed' straight through with a checkpoint
    every third of its path (simulated time); 'segmented' with the same
    checkpoints, its first segment stopped as soon as the first checkpoint
    is written, then resumed by a second call of run_case. femp's restart
    is bit-identical to the run that wrote the checkpoints and went on
    (doc/checkpoint.md), so 'segmented' must equal 'checkpointed' exactly
    (result.json numbers and the time series); 'straight' differs from
    them within the pressure solver's tolerance (a checkpoint restarts the
    solver's preconditioner), printed, not checked."""
    import shutil
    exe = os.path.abspath(os.path.join(args.build, "femp"))
    if not os.path.exists(exe):
        raise SystemExit("validate.py: build femp first (%s)" % exe)
    rx = re.compile(args.cases or r"^trapp_032W$")
    todo = [c for c in cases() if rx.search(c["name"]) and c["v"] > 0]
    if len(todo) != 1:
        raise SystemExit("validate.py resume-check: --cases must match one "
                         "track, it matches %d" % len(todo))
    c = todo[0]
    t_end = path_time(c, args.setting)
    every = "Checkpoint/Every simulated time=%s" % fmt(t_end / 3)
    base = list(args.set or [])
    out, res = args.out, {}
    for name, sets in (("straight", base), ("checkpointed", base + [every]),
                       ("segmented", base + [every]),
                       ("restarted", base + [every])):
        shutil.rmtree(os.path.join(out, name), ignore_errors=True)
        args.out, args.set = os.path.join(out, name), sets
        args.restart_after_checkpoint = name == "restarted"
        d = os.path.join(args.out, args.setting, c["name"])
        if name == "segmented":
            r = run_case(args, exe, c, args.setting,
                         stop=lambda: bool(checkpoints(d)))
            if r is not None:
                raise SystemExit("validate.py resume-check: the first segment "
                                 "was not stopped at its first checkpoint")
        res[name] = run_case(args, exe, c, args.setting)
        res[name]["dir"] = d
    args.out = out
    bad = []
    for name, n_seg in (("segmented", 2), ("restarted", 3)):
        seg = json.load(open(os.path.join(res[name]["dir"], "segments.json")))
        for g in seg:
            print("%s, segment %d: from %s, to t = %s s, %.1f s wall, %.1f s "
                  "CPU, rc %s, %s" % (name, g["segment"], g["resumed_from"] or
                                      "the start", g["t_reached"], g["wall_s"],
                                      g["cpu_s"], g["rc"], g["ended"]))
        if len(seg) != n_seg or not all(g["resumed_from"] for g in seg[1:]):
            bad.append("%s: %d segments, expected %d" % (name, len(seg), n_seg))
    runs = ("straight", "checkpointed", "segmented", "restarted")
    print("%-22s %14s %14s %14s %14s %10s" % (("",) + runs + ("rel.diff",)))
    for k in RESUME_KEYS:
        a, b, x, y = (res[n].get(k) for n in runs)
        if a is None and b is None and x is None and y is None:
            continue
        if b != x or b != y:
            bad.append(k)
        diff = (abs(a - b) / max(abs(b), 1e-300)) if None not in (a, b) else None
        nan = float("nan")
        print("%-22s %14.8g %14.8g %14.8g %14.8g %10s%s" % (
            k, a if a is not None else nan, b if b is not None else nan,
            x if x is not None else nan, y if y is not None else nan,
            "%.1e" % diff if diff is not None else "-",
            "   DIFFERS" if b != x or b != y else ""))
    for f in RESUME_FILES:
        for other in ("segmented", "restarted"):
            fa, fb = (os.path.join(res[n]["dir"], "output", f)
                      for n in ("checkpointed", other))
            if os.path.exists(fa) or os.path.exists(fb):
                same = (os.path.exists(fa) and os.path.exists(fb) and
                        open(fa, "rb").read() == open(fb, "rb").read())
                print("%s, %s: %s" % (f, other, "identical" if same else
                                      "DIFFERS"))
                if not same:
                    bad.append("%s (%s)" % (f, other))
    if bad:
        raise SystemExit("validate.py resume-check: the runs in segments "
                         "differ from the checkpointed one: " + ", ".join(bad))
    print("resume check: the runs in segments equal the checkpointed run")


# ---------------------------------------------------------------- tail
# The track behind the beam (the 'tail' command): field outputs at least
# every 'Output interval' of this setting, in HDF5, with the fields read.
SETTINGS["tail"] = {"Output/Output interval": "2.8e-05",
                    "Output/Format": "hdf5",
                    "Output/Grid fields": "T,gamma,alpha,u_x,u_y,u_z"}


def energy_figures(text):
    """femp's energy line (J) of a run's log: laser (absorbed), evaporation,
    convection, radiation, fixed faces, stored, and the energy created by
    the upwind convection of T and by points moving between cells."""
    r = {}
    m = re.search(r"Energy \(J\): laser ([-0-9.e+]+), surface losses "
                  r"([-0-9.e+]+) \(evaporation ([-0-9.e+]+), convection "
                  r"([-0-9.e+]+), radiation ([-0-9.e+]+) [^)]*\), fixed faces "
                  r"([-0-9.e+]+), stored ([-0-9.e+]+)", text)
    if m:
        r.update(zip(("laser", "losses", "evaporation", "convection",
                      "radiation", "fixed_faces", "stored"),
                     (float(x) for x in m.groups())))
    m = re.search(r"by the upwind convection of T ([-0-9.e+]+), by points "
                  r"moving between cells ([-0-9.e+]+)", text)
    if m:
        r.update(created_upwind=float(m.group(1)),
                 created_moved=float(m.group(2)))
    return r


def enthalpy_table(m, T0):
    """Per unit volume, (T grid, H(T) - H(T0)) of a material() dict: the
    integral of rho c_p from T0 and rho L times the liquid fraction, linear
    between solidus and liquidus."""
    import numpy as np
    Tg = np.linspace(200.0, 6000.0, 5801)
    cg = np.array([m["cp"](T) for T in Tg])
    H = np.concatenate([[0], np.cumsum(0.5 * (cg[1:] + cg[:-1]) * np.diff(Tg))])
    H = m["rho"] * (H + m["L"] * np.clip((Tg - m["Ts"]) / (m["Tl"] - m["Ts"]), 0, 1))
    return Tg, H - np.interp(T0, Tg, H)


def tail_sections(g, sp, m, T0):
    """The cross-sections (y-z slabs of cells) of one field output @p g:
    x of each slab, the enthalpy per unit length above T0 of its metal
    (J/m; rho (H(T) - H(T0)) alpha summed over the slab times h^2, the
    metal above the original surface included), the
    second moments of that enthalpy about the track's axis across (var_y)
    and about the original surface (var_z, the surface a mirror), and the
    temperature on the axis (the mean of the two columns beside it, the
    axis on a cell face; else its column) at the top substrate row and at
    the rows 20, 40 and 80 um below the surface, the slab's fusion
    width at the surface, and its metal section minus the plate's (m^2:
    metal moved along the track)."""
    import numpy as np
    h, ztop, yc = sp["h"], sp["ztop"], sp["start"][1]
    c = np.asarray(g.centres)
    ijk = np.floor(c / h).astype(int)
    n = ijk.max(axis=0) + 1
    T = np.full(n, T0)
    A = np.zeros(n)
    T[tuple(ijk.T)] = g["T"]
    A[tuple(ijk.T)] = g["alpha"]
    Tg, Hg = enthalpy_table(m, T0)
    E = np.interp(T, Tg, Hg) * A * h * h
    y = (np.arange(n[1]) + 0.5) * h - yc
    z = ztop - (np.arange(n[2]) + 0.5) * h
    e_plate = float(E[:, :, z >= 0].sum()) * h  # below the original surface, J
    # metal moved along the track: each slab's metal section against the
    # plate's (the cells below the original surface)
    moved = A.sum(axis=(1, 2)) * h * h - (z >= 0).sum() * n[1] * h * h
    e = E.sum(axis=(1, 2))
    safe = np.where(e > 0, e, 1)
    var_y = (E.sum(axis=2) * y[None, :] ** 2).sum(axis=1) / safe
    var_z = (E.sum(axis=1) * z[None, :] ** 2).sum(axis=1) / safe
    jc = np.argsort(abs(y))[:2] if abs(abs(y).min() - h / 2) < 1e-3 * h \
        else [int(np.argmin(abs(y)))]
    kt = int(round(ztop / h)) - 1
    axis = {"top": T[:, jc, kt].mean(axis=1)}
    for d in (20e-6, 40e-6, 80e-6):
        k = int(round((ztop - d) / h - 0.5))
        axis["%d" % round(d * 1e6)] = T[:, jc, k].mean(axis=1)
    # the width above T_s of each slab at the surface (fusion_width_rows())
    width = [fusion_width_rows(T[i:i + 1], A[i:i + 1], kt, h, m["Ts"])
             ["width_surface"] for i in range(n[0])]
    return dict(x=(np.arange(n[0]) + 0.5) * h, e=e, var_y=var_y, var_z=var_z,
                e_plate=e_plate, moved=moved,
                width=np.array(width), **{"T_" + k: v for k, v in axis.items()})


def tail_reference(q, v, m, T0, d, t_on, rb, face=None):
    """The closed-form temperature on the track's axis at the surface d
    behind a Gaussian surface source of net power q (moving_gaussian_rise()),
    for the property choices (name, k, rho c_p): k and c_p averaged over
    T0..T_s (the Kirchhoff mean: on the axis far behind the source the
    temperature obeys int k dT = q / (2 pi R), whatever c_p), at T_s, and the
    mean with the latent heat spread over T0..T_l (c_p + L / (T_l - T0)).
    Returns {name: (T at the path's end (the source on for t_on), the same
    with the plate's insulated start face @p face behind the source (its
    mirror image of the path added), T quasi-steady)}."""
    Ts, Tl = m["Ts"], m["Tl"]
    mean = lambda f, hi: sum(f(T0 + (hi - T0) * (i + 0.5) / 200)
                             for i in range(200)) / 200
    k_mean, cp_mean = mean(m["k"], Ts), mean(m["cp"], Ts)
    props = (("mean T0..T_s", k_mean, m["rho"] * cp_mean),
             ("at T_s", m["k"](Ts), m["rho"] * m["cp"](Ts)),
             ("mean, latent", k_mean,
              m["rho"] * (cp_mean + m["L"] / (Tl - T0))))
    out = {}
    for name, k, rc in props:
        a = k / rc
        rise = lambda x, t: moving_gaussian_rise(x, 0, 0, q, v, a, rc,
                                                 rb * rb / 4, 0, t)
        end = rise(-d, t_on)
        image = rise(-(2 * face - d), t_on) if face is not None else 0.0
        out[name] = (T0 + end, T0 + end + image, T0 + rise(-d, 0.1))
    return out


def solidus_behind(q, v, m, T0, rb, t_on, k, rc, far=3e-3):
    """How far behind the source the axis at the surface falls below T_s
    (m) in moving_gaussian_rise() with net power q and constant k, rho c_p,
    the source on for t_on (bisection between 2 r_b and @p far, or the
    distance to the path's start v t_on where that is nearer)."""
    a = k / rc
    T = lambda d: T0 + moving_gaussian_rise(-d, 0, 0, q, v, a, rc,
                                            rb * rb / 4, 0, t_on)
    lo, hi = 2 * rb, min(far, v * t_on + 200e-6)
    if T(hi) >= m["Ts"]:
        return hi
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if T(mid) >= m["Ts"] else (lo, mid)
    return lo


def cmd_tail(args):
    """The track behind the beam in the field outputs of finished runs
    (setting 'tail' or any with field outputs): energy balance, the
    enthalpy per unit length of the cross-sections and its spread, the
    temperature on the axis, against the closed-form moving Gaussian source
    with the run's own net power."""
    allc = {c["name"]: c for c in cases()}
    rx_s = re.compile(args.settings or "tail")
    for (setting, name), r in sorted(load_results(args.out).items()):
        if (not re.search(args.cases or ".", name) or not rx_s.search(setting)
                or r.get("incomplete")):
            continue
        c = allc[name]
        d = os.path.join(args.out, setting, name)
        run = femp_post.Run(os.path.join(d, "output"))
        outs = run.outputs("grid")
        if not outs:
            continue
        sp = scene_parameters(d)
        m = material(c["alloy"])
        T0, v = c["T0"], sp["v"]
        t_path = path_time(c, setting)
        en = energy_figures(open(os.path.join(d, "log.txt")).read())
        q_abs = en["laser"] / t_path
        q_net = (en["laser"] - en["losses"]) / t_path
        print("\n%s [%s], h = %g um: path %.0f us; energy (mJ): absorbed %.3f "
              "(%.1f W), evaporation %.3f, convection %.4f, radiation %.4f, "
              "fixed faces %.3f, stored %.3f, created by upwind convection "
              "%.3f, by moved points %.3f; net %.1f W, q_net / v = %.1f J/m" % (
                  name, setting, sp["h"] * 1e6, t_path * 1e6,
                  en["laser"] * 1e3, q_abs, en["evaporation"] * 1e3,
                  en["convection"] * 1e3, en["radiation"] * 1e3,
                  en["fixed_faces"] * 1e3, en["stored"] * 1e3,
                  en.get("created_upwind", 0) * 1e3,
                  en.get("created_moved", 0) * 1e3, q_net, q_net / v))
        n_last, t_last = outs[-1]
        s = tail_sections(run.grid(n_last), sp, m, T0)
        xb = sp["start"][0] + v * min(t_last - sp["t0"], t_path)
        print("  last output t = %.1f us, beam at x = %.1f um; enthalpy above "
              "T0 of the metal below the original surface %.3f mJ, of all "
              "metal %.3f mJ (the log's stored: %.3f)" % (
                  t_last * 1e6, xb * 1e6, s["e_plate"] * 1e3,
                  s["e"].sum() * sp["h"] * 1e3, en["stored"] * 1e3))
        face = xb - (sp["start"][0] - track_geometry(
            c, is_compact(setting), track_length(setting))["start"])
        ref = lambda dd: tail_reference(q_net, v, m, T0, dd, t_path, sp["rb"],
                                        face)
        print("  behind(um)  x(um)  E'(J/m)  sd_y  sd_z(um) width(um) moved(um2)  T_axis: "
              "top  20um  40um  80um (K) | reference at the surface, path's "
              "end / with the start face / steady (K): mean T0..Ts; at Ts; "
              "mean+latent")
        Ts = m["Ts"]
        mean = lambda f: sum(f(T0 + (Ts - T0) * (i + 0.5) / 200)
                             for i in range(200)) / 200
        k_mean, cp_mean = mean(m["k"]), mean(m["cp"])
        step = max(1, int(round(20e-6 / sp["h"])))
        for i in range(len(s["x"]) - 1, -1, -step):
            behind = xb - s["x"][i]
            if behind < -40e-6:
                continue
            rr = ref(behind) if behind > 2 * sp["rb"] else None
            print("  %8.0f %7.0f %8.1f %5.1f %5.1f %6.1f %+7.0f   %6.0f %6.0f %5.0f %5.0f  %s" % (
                behind * 1e6, s["x"][i] * 1e6, s["e"][i],
                math.sqrt(s["var_y"][i]) * 1e6, math.sqrt(s["var_z"][i]) * 1e6,
                s["width"][i] * 1e6, s["moved"][i] * 1e12,
                s["T_top"][i], s["T_20"][i], s["T_40"][i], s["T_80"][i],
                " ".join("%5.0f/%5.0f/%5.0f" % v for v in rr.values())
                if rr else ""))
        for lab, k, cp in (("mean T0..T_s", k_mean, cp_mean),
                           ("at T_s", m["k"](Ts), m["cp"](Ts))):
            rc = m["rho"] * cp
            print("  reference (%s, k %.1f, c_p %.0f): the axis at the surface "
                  "below T_s %.0f um behind the beam at the path's end, %.0f um "
                  "quasi-steady" % (lab, k, cp,
                                    solidus_behind(q_net, v, m, T0, sp["rb"],
                                                   t_path, k, rc) * 1e6,
                                    solidus_behind(q_net, v, m, T0, sp["rb"],
                                                   0.1, k, rc) * 1e6))
        # along the path: per output, the axis at the surface 100, 200 um
        # behind the beam and the enthalpy per length there
        # melt_pool.csv along the path: medians over windows of 30 us
        pool = run.melt_pool()
        cols = (("width_solidus_substrate", "width"),
                ("depth_solidus_substrate", "depth"), ("length", "length"))
        print("  melt_pool.csv, medians over 30 us (um): window (us) | "
              + " | ".join(k for _, k in cols))
        t0 = 0.0
        while t0 < t_path * (1 - 1e-9):
            t1 = min(t0 + 30e-6, t_path)
            vals = [window_stats(pool, key, t0, t1 * (1 + 1e-9))[0]
                    for key, _ in cols]
            print("  %4.0f-%4.0f | %s" % (t0 * 1e6, t1 * 1e6, " | ".join(
                "%6.1f" % (x * 1e6) if x is not None else "     -" for x in vals)))
            t0 = t1
        print("  t(us)  beam x(um) | 100 um behind: T_top E' | 200 um "
              "behind: T_top E'")
        for nn, tt in outs[1:]:
            ss = tail_sections(run.grid(nn), sp, m, T0)
            xbt = sp["start"][0] + v * min(tt - sp["t0"], t_path)
            row = []
            for dd in (100e-6, 200e-6):
                i = int(round((xbt - dd) / sp["h"] - 0.5))
                ok = 0 <= i < len(ss["x"]) and xbt - dd > 0
                row.append("%6.0f %6.1f" % (ss["T_top"][i], ss["e"][i])
                           if ok else "     -      -")
            print("  %5.0f %8.0f | %s | %s" % (tt * 1e6, xbt * 1e6, row[0], row[1]))


# ---------------------------------------------------------------- dig
# What digs the pool, per field output of a run (the 'dig' command). The
# field outputs must be close enough in time for the drilling speed: at
# most DIG_MAX_INTERVAL apart (a keyhole drills about 1 m/s, a cell of 8 um
# in 8 us), which the 'dig' setting gives (HDF5, the fields it reads).
DIG_MAX_INTERVAL = 10e-6
SETTINGS["dig"] = {"Output/Output interval": "5e-06",
                   "Output/Format": "hdf5",
                   "Output/Grid fields": "T,gamma,alpha,u_x,u_y,u_z"}
DIG_COLUMNS = ("time", "x_beam", "depression", "x_deepest_behind_beam",
               "T_deepest", "recoil_deepest", "T_surface_max",
               "x_hottest_behind_beam", "recoil_hottest", "melt_normal_hottest",
               "melt_vertical_hottest", "front_wall_angle", "drilling_speed",
               "u_melt_max", "u_bernoulli_hottest", "recession_hottest",
               "evaporation_W", "absorbed_W", "evaporation_share")


def scene_parameters(run_dir):
    """The scene's values that 'dig' needs, with the run's --set overrides
    (the 'sets' of result.json, else the cell size from the log)."""
    scene = open(os.path.join(run_dir, "scene.prm")).read()
    sets = {}
    f = os.path.join(run_dir, "result.json")
    if os.path.exists(f):
        sets = json.load(open(f)).get("sets", {})

    def value(section_entry, key):
        if section_entry in sets:
            return [float(v) for v in sets[section_entry].split(",")]
        return scene_value(scene, key)
    h = value("Background grid/Cell size", "Cell size")[0]
    log = os.path.join(run_dir, "log.txt")
    if "Background grid/Cell size" not in sets and os.path.exists(log):
        m = re.search(r"background grid: [0-9]+ cells of ([0-9.e+-]+) m",
                      open(log).read())
        h = float(m.group(1)) if m else h
    return dict(h=h, ztop=value("Material points/Substrate top", "Substrate top")[0],
                rb=value("Laser/Beam radius", "Beam radius")[0],
                v=value("Laser/Scan speed", "Scan speed")[0],
                start=value("Laser/Start point", "Start point"),
                end=value("Laser/End point", "End point"),
                t0=(value("Laser/Start time", "Start time") or [0.0])[0],
                zeta_p=value("Melt flow/Recoil coefficient", "Recoil coefficient")[0])


def material_evaporation(alloy):
    """L_v, M, T_v, p_0 and zeta_q of the material file (femp's defaults for
    p_0 and zeta_q where the file does not set them)."""
    text = open(os.path.join(ROOT, "prm", "materials", alloy + ".prm")).read()
    get = lambda key, d=None: float(re.search(
        r"set %s\s*=\s*([^#\n]*)" % re.escape(key), text).group(1)) \
        if re.search(r"set %s\s*=" % re.escape(key), text) else d
    return dict(Lv=get("Latent heat of evaporation"), M=get("Molar mass"),
                Tv=get("Evaporation temperature"), p0=get("Ambient pressure", 101325.0),
                zeta_q=get("Evaporation coefficient", 0.82))


def dig_state(g, sp, mat, ev, t):
    """What digs the pool in one field output @p g (femp_post Fields) at
    time @p t: the metal surface z_s of every column (the topmost crossing
    of alpha = 1/2, interpolated between cell centres), the depression
    depth below the original surface (the deepest z_s within 2 r_b of the
    track axis, from 8 r_b behind to 2 r_b ahead of the beam), the surface
    temperature and the recoil pressure zeta_p p_0 exp(L_v M (T - T_v) /
    (R T T_v)) there and at the hottest surface cell (the cell's own
    temperature, femp's recoil limits it to its surface neighbours' range),
    the melt thickness under the hottest surface cell (from the surface
    into the metal down to the solidus, along the surface normal grad
    alpha / |grad alpha| and vertically), the front wall's angle from the
    vertical (a line x(z) fitted to the centre plane's surface ahead of the
    deepest point, where the depression is 15-85 % of its depth), the
    fastest melt (alpha, gamma >= 1/2) and the evaporated power
    sum q_evap(T) 2 alpha |grad alpha| h^3 over the cells (femp's surface
    loss and its weight, eq. (1), heat capacity of the gas neglected)."""
    import numpy as np
    h = sp["h"]
    c = np.asarray(g.centres)
    ijk = np.floor(c / h).astype(int)
    n = ijk.max(axis=0) + 1
    idx = tuple(ijk.T)
    T = np.zeros(n)
    A = np.zeros(n)
    G = np.zeros(n)
    T[idx], A[idx] = g["T"], g["alpha"]
    if "gamma" in g:
        G[idx] = g["gamma"]
    U2 = np.zeros(n)
    for k in ("u_x", "u_y", "u_z"):
        if k in g:
            U = np.zeros(n)
            U[idx] = g[k]
            U2 += U * U
    x = (np.arange(n[0]) + 0.5) * h
    y = (np.arange(n[1]) + 0.5) * h
    z = (np.arange(n[2]) + 0.5) * h
    (xs, yc), (xe, _) = sp["start"][:2], sp["end"][:2]
    L = math.hypot(xe - xs, sp["end"][1] - sp["start"][1])
    s = min(max(0.0, sp["v"] * (t - sp["t0"])), L)
    xb = xs + s * (xe - xs) / L if L > 0 else xs
    rb, ztop = sp["rb"], sp["ztop"]
    # the metal surface of every column: the topmost cell with alpha >= 1/2
    metal = A >= 0.5
    has = metal.any(axis=2)
    ktop = n[2] - 1 - np.argmax(metal[:, :, ::-1], axis=2)
    ii, jj = np.meshgrid(np.arange(n[0]), np.arange(n[1]), indexing="ij")
    kk = np.clip(ktop, 0, n[2] - 1)
    a_in = A[ii, jj, kk]
    a_up = np.where(kk + 1 < n[2], A[ii, jj, np.minimum(kk + 1, n[2] - 1)], 0.0)
    zs = z[kk] + h * (a_in - 0.5) / np.maximum(a_in - a_up, 1e-12)
    zs = np.where(has, zs, np.nan)
    Tsurf = np.where(has, T[ii, jj, kk], np.nan)
    near = ((abs(y[None, :] - yc) <= 2 * rb) & (x[:, None] >= xb - 8 * rb)
            & (x[:, None] <= xb + 2 * rb) & has)
    r = dict(time=t, x_beam=xb)
    if not near.any():
        return r
    depth = np.where(near, ztop - zs, -np.inf)
    i0, j0 = np.unravel_index(np.argmax(depth), depth.shape)
    R = 8.314462618
    recoil = lambda T_: sp["zeta_p"] * ev["p0"] * math.exp(
        ev["Lv"] * ev["M"] * (T_ - ev["Tv"]) / (R * T_ * ev["Tv"]))
    r.update(depression=max(0.0, float(depth[i0, j0])),
             x_deepest_behind_beam=float(xb - x[i0]),
             T_deepest=float(Tsurf[i0, j0]), recoil_deepest=recoil(Tsurf[i0, j0]))
    hot = np.where(near, Tsurf, -np.inf)
    i1, j1 = np.unravel_index(np.argmax(hot), hot.shape)
    k1 = kk[i1, j1]
    r.update(T_surface_max=float(Tsurf[i1, j1]), x_hottest_behind_beam=float(xb - x[i1]),
             recoil_hottest=recoil(Tsurf[i1, j1]))
    # what the recoil there could do: the speed of melt it pushes out
    # (Bernoulli, sqrt(2 p_r / rho)) and the surface's recession by
    # evaporation alone (q_evap / (rho L_v), femp removes no mass)
    T1 = float(Tsurf[i1, j1])
    q1 = ev["zeta_q"] * ev["Lv"] * ev["M"] * ev["p0"] / math.sqrt(
        2 * math.pi * ev["M"] * R * T1) * math.exp(
        ev["Lv"] * ev["M"] * (T1 - ev["Tv"]) / (R * T1 * ev["Tv"]))
    r["u_bernoulli_hottest"] = math.sqrt(2 * r["recoil_hottest"] / mat["rho"])
    r["recession_hottest"] = q1 / (mat["rho"] * ev["Lv"])

    # melt thickness under the hottest surface cell
    def interp(F, p):
        q = p / h - 0.5
        q0 = np.clip(np.floor(q).astype(int), 0, n - 2)
        f = np.clip(q - q0, 0, 1)
        v = 0.0
        for dx in (0, 1):
            for dy in (0, 1):
                for dz in (0, 1):
                    w = ((f[0] if dx else 1 - f[0]) * (f[1] if dy else 1 - f[1])
                         * (f[2] if dz else 1 - f[2]))
                    v += w * F[q0[0] + dx, q0[1] + dy, q0[2] + dz]
        return v
    grad = np.array([
        (A[min(i1 + 1, n[0] - 1), j1, k1] - A[max(i1 - 1, 0), j1, k1]),
        (A[i1, min(j1 + 1, n[1] - 1), k1] - A[i1, max(j1 - 1, 0), k1]),
        (A[i1, j1, min(k1 + 1, n[2] - 1)] - A[i1, j1, max(k1 - 1, 0)])]) / (2 * h)
    p_surf = np.array([x[i1], y[j1], zs[i1, j1]])

    def thickness(direction):
        """Distance from the alpha = 1/2 crossing along @p direction (unit,
        into the metal) to where T falls below the solidus."""
        step = h / 16
        p = np.array([x[i1], y[j1], z[k1]]) - 2 * h * direction
        start = None
        for m in range(int(40 * h / step)):
            if (p < 0.5 * h).any() or (p > (n - 0.5) * h).any():
                return None
            a = interp(A, p)
            if start is None:
                if a >= 0.5:
                    start = p.copy()
            elif interp(T, p) < mat["Ts"]:
                return float(np.linalg.norm(p - start))
            p = p + step * direction
        return None
    norm = np.linalg.norm(grad)
    r["melt_normal_hottest"] = thickness(grad / norm) if norm > 0 else None
    r["melt_vertical_hottest"] = thickness(np.array([0.0, 0.0, -1.0]))
    del p_surf

    # front wall: the centre plane's surface ahead of the deepest point
    jc = np.nonzero(abs(y - yc) <= 0.5 * h + 1e-12)[0]
    prof = np.nanmean(zs[:, jc], axis=1)
    inside = (x >= xb - 8 * rb) & (x <= xb + 2 * rb)
    dprof = np.where(inside, ztop - prof, -np.inf)
    id_ = int(np.argmax(dprof))
    dmax = dprof[id_]
    pts = []
    for i in range(id_, n[0]):
        if not np.isfinite(dprof[i]) or dprof[i] <= 0:
            break
        if 0.15 * dmax <= dprof[i] <= 0.85 * dmax:
            pts.append((x[i], prof[i]))
    if len(pts) >= 2 and dmax > h:
        px, pz = np.array(pts).T
        slope = np.polyfit(pz, px, 1)[0] if np.ptp(pz) > 0 else 0.0
        r["front_wall_angle"] = float(math.degrees(math.atan(abs(slope))))

    # fastest melt, evaporated power
    melt = (A >= 0.5) & (G >= 0.5)
    r["u_melt_max"] = float(np.sqrt(U2[melt].max())) if melt.any() else 0.0
    ga = np.zeros(n)
    for ax in range(3):
        d = np.gradient(A, h, axis=ax)
        ga += d * d
    ga = np.sqrt(ga)
    surf = (A > 0) & (ga > 1e-12 / h)
    Ts_ = T[surf]
    expo = ev["Lv"] * ev["M"] * (Ts_ - ev["Tv"]) / (R * Ts_ * ev["Tv"])
    q = np.where(expo > -40, ev["zeta_q"] * ev["Lv"] * ev["M"] * ev["p0"]
                 / np.sqrt(2 * math.pi * ev["M"] * R * Ts_)
                 * np.exp(np.minimum(expo, 700)), 0.0)
    r["evaporation_W"] = float(np.sum(q * 2 * A[surf] * ga[surf]) * h ** 3)
    return r


def dig_run(run_dir, alloy, force=False):
    """dig_state of every field output of a run, with the drilling speed
    (central differences of the depression depth in time) and the absorbed
    power of absorption.csv; written to run_dir/dig.csv (kept and reread
    unless the run's outputs are newer, or @p force)."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import femp_post
    out = os.path.join(run_dir, "output")
    f = os.path.join(run_dir, "dig.csv")
    run = femp_post.Run(out)
    index = [os.path.join(out, i) for i in ("grid.xdmf", "grid.pvd")
             if os.path.exists(os.path.join(out, i))]
    if (not force and os.path.exists(f) and index
            and os.path.getmtime(f) >= os.path.getmtime(index[0])):
        rows = csv_rows(f)
        return [{k: (float(v) if v not in ("", None) else None) for k, v in r.items()}
                for r in rows]
    sp = scene_parameters(run_dir)
    mat, ev = material(alloy), material_evaporation(alloy)
    rows = []
    for n, t in run.outputs("grid"):
        rows.append(dig_state(run.grid(n), sp, mat, ev, t))
        print("  %s: t = %.1f us, depression %s um" % (
            os.path.basename(run_dir), t * 1e6, um(rows[-1].get("depression"))),
            flush=True)
    for i, r in enumerate(rows):
        a, b = rows[max(0, i - 1)], rows[min(len(rows) - 1, i + 1)]
        if (a is not b and a.get("depression") is not None
                and b.get("depression") is not None):
            r["drilling_speed"] = (b["depression"] - a["depression"]) / (b["time"] - a["time"])
    ab = os.path.join(out, "absorption.csv")
    if os.path.exists(ab):
        series = [(float(x["time"]), float(x["absorbed"])) for x in csv_rows(ab)]
        for r in rows:
            tt, pa = min(series, key=lambda s: abs(s[0] - r["time"]))
            if abs(tt - r["time"]) <= 1e-5 and pa > 0:
                r["absorbed_W"] = pa
                r["evaporation_share"] = r.get("evaporation_W", 0) / pa
    with open(f, "w") as fh:
        fh.write(",".join(DIG_COLUMNS) + "\n")
        for r in rows:
            fh.write(",".join("" if r.get(k) is None else "%.6g" % r[k]
                              for k in DIG_COLUMNS) + "\n")
    return rows


def dig_summary(rows, sp, t_path, log_text=""):
    """A run's figures from its dig rows: the medians over the last 40 % of
    the path it reached (the quasi-steady keyhole), the drilling phase (the
    depression's mean speed from one cell deep to 90 % of that steady depth,
    and the fastest drilling between outputs), and the evaporation share
    over the run from femp's energy line beside the sum of the outputs."""
    import numpy as np
    rows = [r for r in rows if r.get("depression") is not None]
    if not rows:
        return {}
    t_end = min(t_path, rows[-1]["time"])
    late = [r for r in rows if 0.6 * t_end <= r["time"] <= t_end * (1 + 1e-9)]
    med = lambda k: (float(np.median([r[k] for r in late if r.get(k) is not None]))
                     if any(r.get(k) is not None for r in late) else None)
    s = {k: med(k) for k in DIG_COLUMNS if k not in ("time", "x_beam")}
    s["window_us"] = (0.6 * t_end * 1e6, t_end * 1e6)
    d_ss = s["depression"]
    t1 = next((r["time"] for r in rows if r["depression"] >= sp["h"]), None)
    t9 = next((r["time"] for r in rows if d_ss and r["depression"] >= 0.9 * d_ss), None)
    if t1 is not None and t9 is not None and t9 > t1:
        d1 = next(r["depression"] for r in rows if r["time"] == t1)
        d9 = next(r["depression"] for r in rows if r["time"] == t9)
        s["drilling_mean"] = (d9 - d1) / (t9 - t1)
        s["drilling_window_us"] = (t1 * 1e6, t9 * 1e6)
    ds = [r["drilling_speed"] for r in rows if r.get("drilling_speed") is not None]
    s["drilling_max"] = max(ds) if ds else None
    s["depression_max"] = max(r["depression"] for r in rows)
    lf = log_figures(log_text)
    if lf.get("laser_J"):
        s["evaporation_share_run"] = lf["evaporation_J"] / lf["laser_J"]
        ts = [r["time"] for r in rows]
        pe = [r.get("evaporation_W") or 0.0 for r in rows]
        s["evaporation_J_outputs"] = float(np.trapz(pe, ts))
        s["evaporation_J_log"] = lf["evaporation_J"]
    return s


def cmd_dig(args):
    """'dig': what digs the pool in the runs under --out (settings matching
    --setting-regex, cases --cases) from their field outputs."""
    allc = {c["name"]: c for c in cases()}
    rx_c = re.compile(args.cases or ".")
    rx_s = re.compile(args.settings or ".")
    found = False
    for setting in sorted(os.listdir(args.out)) if os.path.isdir(args.out) else []:
        if not rx_s.search(setting):
            continue
        for name in sorted(os.listdir(os.path.join(args.out, setting))):
            d = os.path.join(args.out, setting, name)
            if name not in allc or not rx_c.search(name) or not os.path.isdir(
                    os.path.join(d, "output")):
                continue
            sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
            import femp_post
            outs = femp_post.Run(os.path.join(d, "output")).outputs("grid")
            c = allc[name]
            t_path = path_time(c, setting)
            gaps = [b[1] - a[1] for a, b in zip(outs, outs[1:])]
            if len(outs) < 3 or max(gaps) > DIG_MAX_INTERVAL * (1 + 1e-6):
                print("%s/%s: %d field outputs, %s us apart: too coarse for the "
                      "drilling speed (at most %.0f us); run it with --setting "
                      "dig (or --set 'Output/Output interval=5e-6')" % (
                          setting, name, len(outs),
                          ("%.0f" % (max(gaps) * 1e6)) if gaps else "-",
                          DIG_MAX_INTERVAL * 1e6))
                continue
            found = True
            rows = dig_run(d, c["alloy"], args.force)
            sp = scene_parameters(d)
            log = os.path.join(d, "log.txt")
            s = dig_summary(rows, sp, t_path, open(log).read() if os.path.exists(log) else "")
            res = os.path.join(d, "result.json")
            r = json.load(open(res)) if os.path.exists(res) else {}
            r["dig"] = s
            if os.path.exists(res):
                json.dump(r, open(res, "w"), indent=1)
            print_dig(setting, name, c, sp, rows, s, r)
    if not found:
        print("validate.py dig: no run with field outputs fine enough under %s"
              % args.out)
        return
    dig_compare(args.out, rx_c, rx_s, allc)


def dig_compare(out, rx_c, rx_s, allc, every=20e-6):
    """The settings of each case side by side (e.g. 8 um cells against a
    4 um window): the output nearest to every @p every, and the medians of
    every setting over the same window, the last 40 % of the shortest
    run."""
    import numpy as np
    runs = {}
    for setting in sorted(os.listdir(out)):
        if not rx_s.search(setting) or not os.path.isdir(os.path.join(out, setting)):
            continue
        for name in sorted(os.listdir(os.path.join(out, setting))):
            f = os.path.join(out, setting, name, "dig.csv")
            if rx_c.search(name) and os.path.exists(f):
                runs.setdefault(name, {})[setting] = csv_rows(f)
    keys = (("depression", 1e6, "%.1f"), ("T_surface_max", 1, "%.0f"),
            ("melt_normal_hottest", 1e6, "%.1f"), ("front_wall_angle", 1, "%.0f"),
            ("u_melt_max", 1, "%.1f"))
    val = lambda r, k: float(r[k]) if r.get(k) not in ("", None) else None

    def cell(rows, k, sc, fm):
        v = [val(r, k) for r in rows if val(r, k) is not None]
        return (fm % (float(np.median(v)) * sc)) if v else "-"
    for name, by in sorted(runs.items()):
        if len(by) < 2:
            continue
        t_last = min(float(rows[-1]["time"]) for rows in by.values())
        print("\n%s: the settings side by side (depression um / hottest surface "
              "K / melt under it along the normal um / front wall deg / fastest "
              "melt m/s)" % name)
        print("%9s " % "t(us)" + " ".join("%30s" % st for st in by))
        t = every
        while t <= t_last + 1e-9:
            line = []
            for rows in by.values():
                r = min(rows, key=lambda x: abs(float(x["time"]) - t))
                line.append(" / ".join(cell([r], k, sc, fm) for k, sc, fm in keys))
            print("%9.0f " % (t * 1e6) + " ".join("%30s" % x for x in line))
            t += every
        win = [r for r in by.values()]
        line = []
        for rows in win:
            late = [r for r in rows if 0.6 * t_last <= float(r["time"]) <= t_last * (1 + 1e-9)]
            line.append(" / ".join(cell(late, k, sc, fm) for k, sc, fm in keys))
        print("%9s " % ("%.0f-%.0f" % (0.6 * t_last * 1e6, t_last * 1e6))
              + " ".join("%30s" % x for x in line) + "  (medians)")
        for st, rows in by.items():
            late = [r for r in rows if 0.6 * t_last <= float(r["time"]) <= t_last * (1 + 1e-9)]
            ds = [(float(r["time"]), val(r, "depression")) for r in rows
                  if float(r["time"]) <= t_last * (1 + 1e-9)]
            print("  %s, %.0f-%.0f us: drilling speed %s m/s (depression from one "
                  "cell to the window's median, mean), evaporation %s of the absorbed "
                  "power, recoil at the hottest cell %s MPa" % (
                      st, 0.6 * t_last * 1e6, t_last * 1e6, drill_mean(ds, late),
                      cell(late, "evaporation_share", 1, "%.3f"),
                      cell(late, "recoil_hottest", 1e-6, "%.2f")))


def drill_mean(ds, late):
    """Mean drilling speed of the depression series @p ds [(t, depth)]: from
    its first nonzero depth to the first that reaches 90 % of the median
    depth of the rows @p late."""
    import numpy as np
    d_ss = float(np.median([float(r["depression"]) for r in late]))
    t1 = next(((t, d) for t, d in ds if d and d > 0), None)
    t9 = next(((t, d) for t, d in ds if d and d >= 0.9 * d_ss), None)
    if not t1 or not t9 or t9[0] <= t1[0]:
        return "-"
    return "%.2f" % ((t9[1] - t1[1]) / (t9[0] - t1[0]))


def print_dig(setting, name, c, sp, rows, s, r):
    f = lambda v, fmt_, scale=1.0: (fmt_ % (v * scale)) if v is not None else "-"
    print("\n%s [%s], %g um cells: %d field outputs to %.0f us (%s)" % (
        name, setting, sp["h"] * 1e6, len(rows), rows[-1]["time"] * 1e6 if rows else 0,
        "wall %.0f s x %d ranks, CPU %.0f s" % (r["wall_s"], r["np"], r.get("cpu_s", 0))
        if r.get("wall_s") else "cost unknown"))
    print("%7s %8s %8s %7s %7s %7s %7s %7s %6s %7s %6s %7s" % (
        "t(us)", "depr(um)", "behind", "T_deep", "p(MPa)", "T_hot", "film_n",
        "film_z", "angle", "v_d", "u_max", "evap"))
    for x in rows:
        print("%7.1f %8s %8s %7s %7s %7s %7s %7s %6s %7s %6s %7s" % (
            x["time"] * 1e6, f(x.get("depression"), "%.1f", 1e6),
            f(x.get("x_deepest_behind_beam"), "%.1f", 1e6), f(x.get("T_deepest"), "%.0f"),
            f(x.get("recoil_deepest"), "%.2f", 1e-6), f(x.get("T_surface_max"), "%.0f"),
            f(x.get("melt_normal_hottest"), "%.1f", 1e6),
            f(x.get("melt_vertical_hottest"), "%.1f", 1e6),
            f(x.get("front_wall_angle"), "%.0f"), f(x.get("drilling_speed"), "%.2f"),
            f(x.get("u_melt_max"), "%.1f"), f(x.get("evaporation_share"), "%.3f")))
    if not s:
        return
    print("medians over %.0f-%.0f us: depression %s um (deepest ever %s um), T there "
          "%s K, recoil there %s MPa; hottest surface %s K (recoil %s MPa), melt "
          "under it %s um along the normal / %s um vertically; front wall %s deg "
          "from the vertical; fastest melt %s m/s; evaporation %s of the absorbed "
          "power" % (s["window_us"][0], s["window_us"][1],
                     f(s.get("depression"), "%.1f", 1e6), f(s.get("depression_max"), "%.1f", 1e6),
                     f(s.get("T_deepest"), "%.0f"), f(s.get("recoil_deepest"), "%.2f", 1e-6),
                     f(s.get("T_surface_max"), "%.0f"), f(s.get("recoil_hottest"), "%.2f", 1e-6),
                     f(s.get("melt_normal_hottest"), "%.1f", 1e6),
                     f(s.get("melt_vertical_hottest"), "%.1f", 1e6),
                     f(s.get("front_wall_angle"), "%.0f"), f(s.get("u_melt_max"), "%.1f"),
                     f(s.get("evaporation_share"), "%.3f")))
    print("at the hottest surface cell: the recoil's Bernoulli speed sqrt(2 p_r/rho) "
          "%s m/s, recession by evaporation alone %s m/s" % (
              f(s.get("u_bernoulli_hottest"), "%.1f"), f(s.get("recession_hottest"), "%.3f")))
    if s.get("drilling_mean") is not None:
        print("drilling: %.2f m/s mean from %.0f to %.0f us (one cell to 90 %% of the "
              "steady depression), %.2f m/s fastest between outputs" % (
                  s["drilling_mean"], s["drilling_window_us"][0],
                  s["drilling_window_us"][1], s["drilling_max"]))
    if s.get("evaporation_share_run") is not None:
        print("evaporation over the run (femp's energy line): %.3f of the absorbed "
              "energy; %.3g J, the outputs' evaporated power integrated: %.3g J" % (
                  s["evaporation_share_run"], s["evaporation_J_log"],
                  s["evaporation_J_outputs"]))


# ---------------------------------------------------------------- report
def load_results(out):
    res = {}
    if not os.path.isdir(out):
        return res
    for setting in sorted(os.listdir(out)):
        sd = os.path.join(out, setting)
        if not os.path.isdir(sd):
            continue
        for name in sorted(os.listdir(sd)):
            f = os.path.join(sd, name, "result.json")
            if os.path.exists(f):
                res[(setting, name)] = json.load(open(f))
    return res


def rel(p, m):
    return (p / m - 1) if (p is not None and m) else None


def retained(r):
    """The fraction of the laser energy that the part keeps, which Trapp's
    calorimetry measures: the absorbed fraction (the window's mean) times
    the share of the absorbed energy that the surface losses (evaporation,
    convection, radiation) leave in the part over the run, 1 - losses /
    laser of femp's energy line; None without them."""
    if r.get("absorbed") is None or not r.get("laser_J") or r.get("losses_J") is None:
        return None
    return r["absorbed"] * (1 - r["losses_J"] / r["laser_J"])


def pct(x):
    return ("%+.0f %%" % (100 * x)) if x is not None else "-"


def svg_scatter(path, series, title, xlabel, ylabel, diag=True,
                xlim=None, ylim=None, pad=True, lines=False):
    """Predicted against measured (or any x-y) with horizontal error bars
    (the measurement's spread) and the line y = x (diag). series: list of
    (label, colour, [(x, y, xerr, yerr, text)]). pad: widen the axes by 8 %;
    lines: join each series' points in the order given (True), or only
    those of the series whose labels it holds (a tuple)."""
    W, Hh, L, R, T, B = 560, 460, 70, 150, 40, 55
    xs = [p[0] for s in series for p in s[2]] or [0, 1]
    ys = [p[1] for s in series for p in s[2]] or [0, 1]
    lo = min(xs + ys) if diag else None
    hi = max(xs + ys) if diag else None
    x0, x1 = xlim or ((lo, hi) if diag else (min(xs), max(xs)))
    y0, y1 = ylim or ((lo, hi) if diag else (min(ys), max(ys)))
    padx, pady = ((0.08 * (x1 - x0 or 1), 0.08 * (y1 - y0 or 1)) if pad
                  else (0.0, 0.0))
    x0, x1, y0, y1 = x0 - padx, x1 + padx, y0 - pady, y1 + pady
    X = lambda v: L + (v - x0) / (x1 - x0) * (W - L - R)
    Y = lambda v: Hh - B - (v - y0) / (y1 - y0) * (Hh - T - B)
    o = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" '
         'font-family="sans-serif" font-size="11">' % (W, Hh),
         '<rect width="100%" height="100%" fill="white"/>',
         '<text x="%d" y="20" font-size="13">%s</text>' % (L, title)]
    for i in range(6):
        xv = x0 + (x1 - x0) * i / 5
        yv = y0 + (y1 - y0) * i / 5
        o.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#eee"/>'
                 % (X(xv), T, X(xv), Hh - B))
        o.append('<text x="%.1f" y="%d" text-anchor="middle">%.3g</text>'
                 % (X(xv), Hh - B + 15, xv))
        o.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#eee"/>'
                 % (L, Y(yv), W - R, Y(yv)))
        o.append('<text x="%d" y="%.1f" text-anchor="end">%.3g</text>'
                 % (L - 5, Y(yv) + 4, yv))
    o.append('<rect x="%d" y="%d" width="%d" height="%d" fill="none" '
             'stroke="black"/>' % (L, T, W - L - R, Hh - T - B))
    if diag:
        a, b = max(x0, y0), min(x1, y1)
        o.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="#888" '
                 'stroke-dasharray="4 3"/>' % (X(a), Y(a), X(b), Y(b)))
    o.append('<text x="%d" y="%d" text-anchor="middle">%s</text>'
             % ((L + W - R) // 2, Hh - 15, xlabel))
    o.append('<text x="16" y="%d" text-anchor="middle" transform="rotate(-90 '
             '16 %d)">%s</text>' % ((T + Hh - B) // 2, (T + Hh - B) // 2, ylabel))
    for k, (label, colour, pts) in enumerate(series):
        if (lines is True or (lines and label in lines)) and len(pts) > 1:
            o.append('<polyline fill="none" stroke="%s" points="%s"/>' % (
                colour, " ".join("%.1f,%.1f" % (X(p[0]), Y(p[1])) for p in pts)))
        for (x, y, xe, ye, text) in pts:
            if xe:
                o.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" '
                         'stroke="%s"/>' % (X(x - xe), Y(y), X(x + xe), Y(y), colour))
            if ye:
                o.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" '
                         'stroke="%s"/>' % (X(x), Y(y - ye), X(x), Y(y + ye), colour))
            o.append('<circle cx="%.1f" cy="%.1f" r="3.5" fill="%s"/>'
                     % (X(x), Y(y), colour))
            if text:
                o.append('<text x="%.1f" y="%.1f" font-size="9">%s</text>'
                         % (X(x) + 5, Y(y) - 4, text))
        o.append('<circle cx="%d" cy="%d" r="4" fill="%s"/>'
                 % (W - R + 12, T + 12 + 16 * k, colour))
        o.append('<text x="%d" y="%d">%s</text>' % (W - R + 20, T + 16 + 16 * k, label))
    o.append("</svg>")
    with open(path, "w") as fh:
        fh.write("\n".join(o) + "\n")


SETTING_NAMES = {"default": "default free surface, 8 um cells",
                 "h4": "default free surface, 4 um cells",
                 "h2": "default free surface, 2 um cells",
                 "fine": "fine surface (height function, 2 smoothing passes, "
                         "point shifting 2), 8 um cells",
                 "large": "default free surface, domain 1.5 x wider and deeper",
                 "compact": "default free surface, compact domain (shorter "
                            "track, smaller plate)",
                 "median": "recoil from the median surface temperature "
                           "(former default)",
                 "cell": "recoil from the cell's own temperature",
                 "thermal": "no melt flow (diagnostic)",
                 "nomarangoni": "no Marangoni stress (diagnostic)",
                 "evapmass": "default free surface, evaporated mass removed, "
                             "8 um cells",
                 "film": "default free surface, front-wall film slip, "
                         "8 um cells",
                 "piston": "default free surface, front-wall piston, "
                           "8 um cells",
                 "expel": "default free surface, front-wall expulsion, "
                          "8 um cells",
                 "kulr19": "default free surface, KU Leuven spot read as a "
                           "37.5 um 1/e^2 diameter (r_b 18.75 um), 8 um cells"}
# the retained fraction in the absorption figure, a lighter tone of COLOURS
RETAINED_COLOURS = {"default": "#74c0fc", "h4": "#8ce99a", "h2": "#66d9e8",
                    "fine": "#ffa94d", "median": "#ced4da", "cell": "#e599f7"}
COLOURS = {"default": "#1f5fbf", "h4": "#2b8a3e", "h2": "#0b7285",
           "fine": "#d9480f", "large": "#5c940d", "median": "#868e96",
           "cell": "#ae3ec9", "thermal": "#e67700", "nomarangoni": "#c2255c",
           "evapmass": "#5f3dc4", "film": "#087f5b",
           "piston": "#e8590c", "expel": "#495057"}
# Settings drawn in the figures (the validation's own; diagnostics and the
# domain-size check are in the tables only).
FIGURE_SETTINGS = ("default", "h4", "h2", "fine", "median", "cell")


def setting_order(res):
    known = list(SETTING_NAMES)
    present = sorted({k[0] for k in res},
                     key=lambda s: (known.index(s) if s in known else len(known), s))
    return present


def cmd_report(args):
    res = load_results(args.out)
    RES_OUT[0] = args.out
    allc = {c["name"]: c for c in cases()}
    os.makedirs(args.img, exist_ok=True)
    settings = setting_order(res)
    # figures
    for what in ("width", "depth"):
        series = []
        for s in settings:
            if s not in FIGURE_SETTINGS:
                continue
            pts = []
            for (st, name), r in sorted(res.items()):
                c = allc.get(name)
                # the spot sweep has its own figures (nist_spot_figures)
                # the KU Leuven tracks (trends only) have their own table
                if (st != s or not c or r.get(what) is None
                        or c["dataset"] in ("NIST spot sweep",
                                            "KU Leuven 2022")):
                    continue
                pts.append((c[what] * 1e6, r[what] * 1e6, c[what + "_sd"] * 1e6,
                            0, c["label"] if s == "default" else ""))
            if pts:
                series.append((SETTING_NAMES[s].split(" (")[0].replace(
                    "default free surface, ", "femp, "), COLOURS[s], pts))
        if series:
            svg_scatter(os.path.join(args.img, "validation_%s.svg" % what), series,
                        "Fusion-zone %s: femp against measured" % what,
                        "measured %s (um), bar: spread" % what,
                        "femp %s (um)" % what)
    series = []
    meas = [(c["P"], c["absorptivity"], 0, 0.005, "") for c in cases()
            if c["dataset"] == "Trapp 2017" and c.get("absorptivity")]
    series.append(("Trapp 2017 calorimetry", "#000000", meas))
    for s in settings:
        if s not in FIGURE_SETTINGS:
            continue
        pts = [(allc[n]["P"], r["absorbed"], 0, 0, "")
               for (st, n), r in sorted(res.items())
               if st == s and n.startswith("trapp") and r.get("absorbed") is not None]
        if pts:
            series.append((SETTING_NAMES[s].split(" (")[0].replace(
                "default free surface, ", "femp, "), COLOURS[s], pts))
        # what the part retains (the calorimetry's quantity, retained())
        pts = [(allc[n]["P"], retained(r), 0, 0, "")
               for (st, n), r in sorted(res.items())
               if st == s and n.startswith("trapp") and retained(r) is not None]
        if pts:
            series.append(("femp retained" + ("" if s == "default" else ", " + s),
                           RETAINED_COLOURS[s], pts))
    svg_scatter(os.path.join(args.img, "validation_absorption.svg"), series,
                "Absorbed and retained fraction at 500 mm/s, 316L, against "
                "power", "laser power (W)", "fraction of the laser energy",
                diag=False, ylim=(0, 1))
    nist_spot_figures(res, allc, settings, args.img)
    # tables
    lines = []
    for ds in ("AM-Bench 2022", "NIST spot sweep", "Trapp 2017"):
        rows = [(st, n, r) for (st, n), r in sorted(res.items())
                if n in allc and allc[n]["dataset"] == ds]
        if not rows:
            continue
        lines.append("\n### %s\n" % ds)
        trapp = ds == "Trapp 2017"
        lines.append("| case | setting | measured width (µm) | femp | error | "
                     "measured depth (µm) | femp | error | depth/width | "
                     "absorbed (femp%s) | %shits/ray | ΔH/h_s | steady (depth growth) | "
                     "wall (s) × ranks |" % ((" / Trapp", "retained (femp / Trapp) | ")
                                             if trapp else ("", "")))
        lines.append("|---|---|" + "---:|" * (13 if trapp else 12))
        for st, n, r in sorted(rows, key=lambda x: (x[1], settings.index(x[0]))):
            c = allc[n]
            ab = ("%.3f" % r["absorbed"]) if r.get("absorbed") is not None else "-"
            if trapp:
                cal = (" / %.3f" % c["absorptivity"]) if c.get("absorptivity") else " / -"
                ret = retained(r)
                ab += cal + " | " + (("%.3f" % ret) if ret is not None else "-") + cal
            lines.append("| %s | %s | %.1f ± %.1f | %s | %s | %.1f ± %.1f | %s | %s | "
                         "%.2f | %s | %s | %s | %s | %.0f × %d%s |" % (
                             c["label"], st, c["width"] * 1e6, c["width_sd"] * 1e6,
                             um(r.get("width")), pct(rel(r.get("width"), c["width"])),
                             c["depth"] * 1e6, c["depth_sd"] * 1e6, um(r.get("depth")),
                             pct(rel(r.get("depth"), c["depth"])),
                             c["depth"] / c["width"], ab,
                             ("%.2f" % r["hits_per_ray"]) if r.get("hits_per_ray") else "-",
                             ("%.3g" % r["normalized_enthalpy"]) if r.get("normalized_enthalpy") else "-",
                             pct(r.get("depth_growth")),
                             # runs started by hand carry femp's own wall time
                             r.get("wall_s") or r.get("femp_wall_s") or 0, r["np"],
                             (" (stopped at %.0f of %.0f µs)" % (
                                 r["t_reached"] * 1e6,
                                 path_time(c, st) * 1e6))
                             if r.get("incomplete") else ""))
    lines += kul_table(res, allc, settings)
    lines += dig_table(res, allc, settings)
    table = "\n".join(lines) + "\n"
    f = os.path.join(args.out, "tables.md")
    open(f, "w").write(table)
    print(table)
    print("wrote", f, "and the figures in", args.img)


def ranks(x):
    """The ranks of the values @p x (1 = smallest; ties share their mean
    rank)."""
    order = sorted(range(len(x)), key=lambda i: x[i])
    r = [0.0] * len(x)
    i = 0
    while i < len(order):
        j = i
        while j + 1 < len(order) and x[order[j + 1]] == x[order[i]]:
            j += 1
        for k in range(i, j + 1):
            r[order[k]] = 0.5 * (i + j) + 1
        i = j + 1
    return r


def spearman(x, y):
    """Spearman's rank correlation of @p x and @p y (None for fewer than
    3 pairs or a constant series)."""
    if len(x) < 3:
        return None
    rx, ry = ranks(x), ranks(y)
    mx, my = sum(rx) / len(rx), sum(ry) / len(ry)
    sxy = sum((a - mx) * (b - my) for a, b in zip(rx, ry))
    sxx = sum((a - mx) ** 2 for a in rx)
    syy = sum((b - my) ** 2 for b in ry)
    return sxy / math.sqrt(sxx * syy) if sxx > 0 and syy > 0 else None


def regime_of(dh):
    """femp's scene-log class of a normalized enthalpy (source/app/scene.cc):
    conduction below 2.5, near the transition to 3, transition or keyhole
    from 3."""
    if dh is None:
        return "-"
    return ("conduction" if dh < 2.5 else "near transition" if dh < 3
            else "transition/keyhole")


def kul_table(res, allc, settings):
    """The KU Leuven 316L tracks (Coen et al. 2022; a secondary data set,
    trends only): per case femp's width and depth against the measured
    ones, depth/width, the normalized enthalpy of the scene log and its
    class against the authors' regime; per power and setting the trends
    with speed: Spearman's rank correlation of width and depth with the
    speed and the ratio of the slowest to the fastest track's depth,
    femp's and measured on the same cases. No pass/fail."""
    rows = [(st, n, r) for (st, n), r in res.items()
            if n in allc and allc[n]["dataset"] == "KU Leuven 2022"]
    if not rows:
        return []
    out = ["\n### KU Leuven 2022 (316L, trends only)\n",
           "| case | setting | measured width (µm) | femp | error | measured "
           "depth (µm) | femp | error | depth/width measured / femp | "
           "regime (authors) | ΔH/h_s | femp's class | absorbed (femp) | "
           "wall (s) × ranks |",
           "|---|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---|---:|---:|"]
    for st, n, r in sorted(rows, key=lambda x: (allc[x[1]]["P"], settings.index(x[0]),
                                               allc[x[1]]["v"])):
        c = allc[n]
        dh = r.get("normalized_enthalpy")
        dw = (("%.2f" % (r["depth"] / r["width"]))
              if r.get("depth") and r.get("width") else "-")
        out.append("| %s | %s | %.1f | %s | %s | %.1f | %s | %s | %.2f / %s | %s | "
                   "%s | %s | %s | %.0f × %d%s |" % (
                       c["label"], st, c["width"] * 1e6, um(r.get("width")),
                       pct(rel(r.get("width"), c["width"])), c["depth"] * 1e6,
                       um(r.get("depth")), pct(rel(r.get("depth"), c["depth"])),
                       c["depth"] / c["width"], dw, c["regime"],
                       ("%.2f" % dh) if dh else "-", regime_of(dh),
                       ("%.3f" % r["absorbed"]) if r.get("absorbed") is not None else "-",
                       r.get("wall_s") or r.get("femp_wall_s") or 0, r["np"],
                       " (incomplete)" if r.get("incomplete") else ""))
    out += ["", "Trends with the speed (the cases femp ran; Spearman's rank "
            "correlation with the speed, −1: falls monotonically; depth ratio: "
            "slowest over fastest track):", "",
            "| power | setting | speeds (mm/s) | width ρ measured / femp | "
            "depth ρ measured / femp | depth ratio measured / femp |",
            "|---|---|---|---:|---:|---:|"]
    for P in sorted({allc[n]["P"] for _, n, _ in rows}):
        for st in settings:
            sel = sorted((allc[n]["v"], allc[n], r) for s, n, r in rows
                         if s == st and allc[n]["P"] == P and r.get("width")
                         and r.get("depth") and not r.get("incomplete"))
            if not sel:
                continue
            v = [x[0] for x in sel]

            def rho(key, femp):
                y = [(x[2][key] if femp else x[1][key]) for x in sel]
                q = spearman(v, y)
                return ("%+.2f" % q) if q is not None else "-"

            def ratio(femp):
                a, b = (sel[0][2], sel[-1][2]) if femp else (sel[0][1], sel[-1][1])
                return "%.2f" % (a["depth"] / b["depth"]) if len(sel) > 1 else "-"

            out.append("| %g W | %s | %s | %s / %s | %s / %s | %s / %s |" % (
                P, st, ", ".join("%g" % (x * 1e3) for x in v),
                rho("width", False), rho("width", True),
                rho("depth", False), rho("depth", True), ratio(False), ratio(True)))
    return out


def nist_spot_figures(res, allc, settings, img):
    """The NIST spot-size sweep (285 W, 960 mm/s, IN718): femp's width and
    depth against the measured ones (bar: the expanded uncertainty), and
    both against the spot diameter (the trend), measured and femp's."""
    figs = [s for s in settings if s in FIGURE_SETTINGS + ("expel",)]
    runs = {s: sorted((allc[n]["rb"], allc[n], r) for (st, n), r in res.items()
                      if st == s and n in allc
                      and allc[n]["dataset"] == "NIST spot sweep"
                      and r.get("width") is not None and not r.get("incomplete"))
            for s in figs}
    runs = {s: v for s, v in runs.items() if v}
    if not runs:
        return
    name = lambda s: "femp" if s == "default" else "femp, " + s
    spot = lambda c: "%.0f um" % (2e6 * c["rb"])
    # default: depth orange, width blue; a second setting in lighter tones
    colour = lambda what, s: {("depth", True): "#d9480f", ("width", True): "#1f5fbf",
                              ("depth", False): "#f59f00",
                              ("width", False): "#15aabf"}[(what, s == "default")]
    series = []
    for what in ("width", "depth"):
        for s, v in runs.items():
            series.append(("%s, %s" % (what, name(s)) if len(runs) > 1 else what,
                           colour(what, s),
                           [(c[what] * 1e6, r[what] * 1e6, c[what + "_sd"] * 1e6,
                             0, spot(c) if s == "default" else "")
                            for _, c, r in v]))
    svg_scatter(os.path.join(img, "validation_nist_spot.svg"), series,
                "NIST spot sweep (IN718, 285 W, 960 mm/s): femp against measured",
                "measured width, depth (um), bar: expanded uncertainty",
                "femp (um)")
    meas = sorted({c["name"]: c for v in runs.values() for _, c, _ in v}.values(),
                  key=lambda c: c["rb"])
    series = [("measured depth", "#000000",
               [(2e6 * c["rb"], c["depth"] * 1e6, 0, c["depth_sd"] * 1e6, "")
                for c in meas]),
              ("measured width", "#868e96",
               [(2e6 * c["rb"], c["width"] * 1e6, 0, c["width_sd"] * 1e6, "")
                for c in meas])]
    for s, v in runs.items():
        for what in ("depth", "width"):
            series.append(("%s, %s" % (what, name(s)), colour(what, s),
                           [(2e6 * c["rb"], r[what] * 1e6, 0, 0, "")
                            for _, c, r in v]))
    svg_scatter(os.path.join(img, "validation_nist_spot_trend.svg"), series,
                "NIST spot sweep: fusion zone against spot diameter",
                "spot diameter D4sigma (um)", "width, depth (um)", diag=False,
                xlim=(40, 90), ylim=(0, 300), pad=False, lines=True)


def dig_table(res, allc, settings):
    """What digs the pool and what sets the width, for every finished run
    with a field output at the end: the depression on the beam axis and its
    deepest point (end_state), the hottest surface (median of T_max) and
    the recoil zeta_p p_sat there, the share of the absorbed energy that
    evaporation takes, the fastest melt, and the width diagnostics
    (width_state)."""
    lines = ["\n### What digs the pool and what sets the width\n",
             "| case | setting | width (µm) | depth (µm) | depression on the axis / "
             "deepest (µm) | hottest surface T (K) | ζ_p p_sat there (MPa) | "
             "evaporation / absorbed | fastest melt (m/s) | widest section behind "
             "the beam (µm) | surface flow across the track, whole pool / "
             "rim (m/s, − inward) | width at the end: top row / surface (µm) |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for (st, n), r in sorted(res.items(),
                             key=lambda x: (x[0][1], settings.index(x[0][0]))):
        c = allc.get(n)
        if not c or r.get("incomplete") or r.get("width") is None:
            continue
        try:
            w = width_state(os.path.join(RES_OUT[0], st, n), c["alloy"])
        except (OSError, ValueError, KeyError, IndexError):
            w = {}
        Lv, M, Tv = EVAPORATION[c["alloy"]]
        p = lambda T: 0.54 * 101325 * math.exp(Lv * M * (T - Tv) / (8.314462618 * T * Tv))
        f2 = lambda v: ("%+.2f" % v) if v is not None else "-"
        ev = (r["evaporation_J"] / r["laser_J"]) if r.get("laser_J") else None
        lines.append("| %s | %s | %s | %s | %s / %s | %.0f | %.2f | %s | %s | %s | %s / %s | %s / %s |" % (
            c["label"], st, um(r["width"]), um(r["depth"]),
            um(r.get("depression_axis")), um(r.get("depression")), r["T_max"],
            p(r["T_max"]) / 1e6, ("%.0f %%" % (100 * ev)) if ev is not None else "-",
            ("%.1f" % r["u_max"]) if r.get("u_max") is not None else "-",
            um(w.get("x_behind_beam")), f2(w.get("flow_across_surface")),
            f2(w.get("flow_across_rim")), um(w.get("width_top_row")),
            um(w.get("width_surface"))))
    return lines


RES_OUT = [None]


# ---------------------------------------------------------------- pipeline
def cmd_pipeline(args):
    """Trapp 48 W, thermal only, 16 um cells, 0.2 ms: the whole chain."""
    exe = os.path.abspath(os.path.join(args.build, "femp"))
    c = [c for c in cases() if c["name"] == "trapp_048W"][0]
    d = os.path.abspath(args.out)
    os.makedirs(d, exist_ok=True)
    scene = os.path.join(d, "scene.prm")
    text = scene_text(c).replace("include ../materials/",
                                 "include %s/prm/materials/" % ROOT)
    open(scene, "w").write(text)
    t_end = 2e-4
    sets = {"Physics/Melt flow": "false", "Background grid/Cell size": "16e-6",
            "Material points/Point spacing": "8e-6",
            "Time stepping/End time": str(t_end),
            "Output/Directory": os.path.join(d, "output"),
            "Output/Time series interval": "5e-6",
            # the pool from a third of the part of the track it runs on
            "Output/Melt pool from x": fmt(track_geometry(c)["start"] +
                                           c["v"] * t_end / 3)}
    args.np = 1
    rc, wall, cpu = run_timed(femp_cmd(args, exe, sets, scene), d,
                         os.path.join(d, "log.txt"))
    if rc != 0:
        raise SystemExit("validate.py pipeline: femp failed (exit %d), see %s"
                         % (rc, os.path.join(d, "log.txt")))
    r = evaluate(os.path.join(d, "output"), t_end, open(os.path.join(d, "log.txt")).read())
    out = ["case trapp_048W (thermal only, 16 um, 0.2 ms)",
           "fusion-zone width (um) = %.0f" % (r["width"] * 1e6),
           "fusion-zone depth (um) = %.0f" % (r["depth"] * 1e6),
           "width error against Trapp 2017 = %.2f" % rel(r["width"], c["width"]),
           "depth error against Trapp 2017 = %.2f" % rel(r["depth"], c["depth"]),
           "absorbed fraction = %.3f (Trapp 2017: %.3f)" % (r["absorbed"], c["absorptivity"]),
           "flat-surface Fresnel value of the 316L constants = %.3f" % fresnel(3.83, 5.34)]
    text = "\n".join(out) + "\n"
    print(text, end="")
    if args.expected:
        exp = open(args.expected).read()
        if not same_numbers(exp, text):
            raise SystemExit("validate.py pipeline: output differs from %s" % args.expected)
        print("pipeline output agrees with", args.expected)


def fresnel(n, k):
    return 4 * n / ((n + 1) ** 2 + k ** 2)


def same_numbers(a, b, rtol=1e-6):
    na = re.findall(r"-?[0-9]+\.?[0-9]*(?:e[-+]?[0-9]+)?", a)
    nb = re.findall(r"-?[0-9]+\.?[0-9]*(?:e[-+]?[0-9]+)?", b)
    words = lambda s: re.sub(r"-?[0-9]+\.?[0-9]*(?:e[-+]?[0-9]+)?", "#", s)
    if words(a) != words(b) or len(na) != len(nb):
        return False
    return all(abs(float(x) - float(y)) <= rtol * max(1, abs(float(x)))
               for x, y in zip(na, nb))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("command", choices=["scenes", "run", "reevaluate", "report", "all",
                                       "pipeline", "regime", "width", "conduction",
                                       "conduction3d", "spots", "dig", "tail",
                                       "resume-check"])
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--cases", default=None)
    ap.add_argument("--setting", default="default",
                    help="default, fine, large, compact, h4, h2, ... (named "
                    "settings joined by '+', e.g. h2+compact), or any other "
                    "name for a run with --set overrides")
    ap.add_argument("--set", action="append", metavar="SECTION/ENTRY=VALUE",
                    help="a femp parameter for this setting (repeatable)")
    ap.add_argument("--np", type=int, default=2)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--out", default=None)
    ap.add_argument("--img", default=os.path.join(ROOT, "doc", "img"))
    ap.add_argument("--max-wall", type=float, default=None,
                    help="run: stop each femp run after this many seconds of "
                    "wall time (with checkpoints: the segment's end; the same "
                    "command resumes it)")
    ap.add_argument("--restart-after-checkpoint", action="store_true",
                    help="run: end femp after each checkpoint it writes before "
                    "the end and resume in a new process")
    ap.add_argument("--checkpoint-minutes", type=float, default=None,
                    help="run: femp writes a checkpoint every this many minutes "
                    "of wall time into <run>/checkpoint (the last two kept); a "
                    "run stopped before its end is resumed from there by the "
                    "same command")
    ap.add_argument("--expected", default=None)
    ap.add_argument("--h", default=None, help="conduction3d: cell sizes, um, e.g. '8,4'")
    ap.add_argument("--end-time", type=float, default=None,
                    help="spots: simulated time, s (default 1.5 x the measured "
                    "keyhole onset, at least 0.4 ms)")
    ap.add_argument("--eta", type=float, default=None,
                    help="conduction3d: absorbed fraction (default: the measured one)")
    ap.add_argument("--settings", default=None,
                    help="dig: the settings (run directories) to read, a regex "
                    "(default: every one with field outputs fine enough)")
    ap.add_argument("--force", action="store_true",
                    help="dig: evaluate again where dig.csv exists")
    ap.add_argument("--props", default=None,
                    help="conduction3d: 'file', 'nolatent', 'const' (comma-separated)")
    ap.add_argument("--evap", action="store_true",
                    help="conduction3d: the surface loses femp's evaporation flux")
    args = ap.parse_args()
    if args.out is None:
        args.out = os.path.join(args.build, {"pipeline": "validation_pipeline",
                                             "resume-check": "validation_resume"}
                                .get(args.command, "validation"))
    # femp runs in the run directory: a relative --out must not be read
    # from there
    args.out = os.path.abspath(args.out)
    if args.command == "scenes":
        cmd_scenes(args)
    elif args.command == "run":
        cmd_run(args)
    elif args.command == "regime":
        cmd_regime(args)
    elif args.command == "conduction":
        cmd_conduction(args)
    elif args.command == "conduction3d":
        cmd_conduction3d(args)
    elif args.command == "spots":
        cmd_spots(args)
    elif args.command == "width":
        cmd_width(args)
    elif args.command == "dig":
        cmd_dig(args)
    elif args.command == "tail":
        cmd_tail(args)
    elif args.command == "reevaluate":
        cmd_reevaluate(args)
    elif args.command == "report":
        cmd_report(args)
    elif args.command == "all":
        cmd_run(args)
        cmd_report(args)
    elif args.command == "resume-check":
        cmd_resume_check(args)
    else:
        cmd_pipeline(args)


if __name__ == "__main__":
    main()
