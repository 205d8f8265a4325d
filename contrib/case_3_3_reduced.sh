#!/bin/bash
# The paper's case 3.3 (single track at 50, 100 and 200 W) and the FEMP
# against all-MPM comparison of its Fig. 8, at the reduced scale of the
# default scene prm/case_3_2_reduced.prm (8 um cells, 100 um of track in
# 50 us, cooling to 150 us; doc/cases.md "Reduced cases 3.2 and 3.3").
# The paper-scale scenes (prm/case_3_3_*W.prm) take many hours each on 2
# cores; these runs take a few minutes each.
#
#   contrib/case_3_3_reduced.sh [NPROC] [OUTPUT_ROOT] [FIGURE_DIR]
#
# (defaults 2, output/reduced, doc/figures), run from the repository root
# with build/femp built. Writes
#   OUTPUT_ROOT/{50W,100W,200W}  the three powers by FEMP to 150 us, field
#                                output every 20 us (number 2: t = 40 us,
#                                the beam at x = 140 um, 80 % of the track)
#   OUTPUT_ROOT/200W_mpm         200 W by all-MPM to 40 us
# and the figures
#   FIGURE_DIR/case_3_2_reduced_femp_vs_mpm.svg  T on CD, sigma_xx on CD and
#       EF at 40 us, FEMP and all-MPM (the paper's Fig. 8);
#   FIGURE_DIR/case_3_3_reduced_power.svg  T and sigma_xx on CD at 40 us
#       for the three powers (the paper's Figs 9-10);
# and prints the table of pool size, bead size and peak stresses against
# the power (doc/cases.md; the files read by contrib/femp_post.py, numpy). MPIRUN overrides the MPI launcher (default:
# mpirun; e.g. MPIRUN="mpirun --allow-run-as-root --oversubscribe");
# NO_RUN=1 only redraws the figures and the table from existing output.
# On a machine shared with other jobs, 1 rank can be much faster than 2
# (waiting MPI ranks spin; doc/cases.md).
set -e
NP=${1:-2}
ROOT=${2:-output/reduced}
FIG=${3:-doc/figures}
MPIRUN=${MPIRUN:-mpirun}
SCENE=prm/case_3_2_reduced.prm
mkdir -p "$ROOT" "$FIG"

run() { # directory, extra --set arguments
  local dir=$1; shift
  echo "== $dir"
  $MPIRUN -np "$NP" build/femp --set "Output/Directory=$dir" \
    --set "Output/Output interval=2e-5" --set "Output/Write material points=never" \
    "$@" "$SCENE" > "$dir.log" 2>&1 || { tail -20 "$dir.log"; exit 1; }
  tail -1 "$dir.log"
}

if [ -z "$NO_RUN" ]; then
  for P in 50 100 200; do
    run "$ROOT/${P}W" --set "Laser/Power=$P"
  done
  run "$ROOT/200W_mpm" --set "Solid FEM/Use finite elements=false" \
    --set "Time stepping/End time=4e-5"
fi

python3 contrib/plot_track_svg.py --compare "$FIG/case_3_2_reduced_femp_vs_mpm.svg" --n 2 \
  "$ROOT/200W=FEMP" "$ROOT/200W_mpm=all-MPM" CD:T CD:sigma_xx EF:sigma_xx
python3 contrib/plot_track_svg.py --compare "$FIG/case_3_3_reduced_power.svg" --n 2 \
  "$ROOT/50W=50 W" "$ROOT/100W=100 W" "$ROOT/200W=200 W" CD:T CD:sigma_xx

python3 - "$ROOT" "$(dirname "$0")" <<'PY'
import sys
sys.path.insert(0, sys.argv[2])
import femp_post  # the run's files as arrays (contrib/femp_post.py)
root = sys.argv[1]
print("| power | pool L x W x D at 40 us (um) | largest pool L x W x D (um) "
      "| fusion zone in the substrate, largest W x D (um) "
      "| bead at 150 us: cross-section W x H, centre line L x H (um) "
      "| CD at 40 us: T max (K), sigma_xx peak, von Mises max (MPa), plastic strain max "
      "| CD at 150 us: sigma_xx min / max, von Mises max (MPa) |")
print("|---|---|---|---|---|---|---|")
for p in (50, 100, 200):
    run = femp_post.Run("%s/%dW" % (root, p))
    pool = run.melt_pool()
    times = pool["time"].tolist()
    i_at = min(range(len(times)), key=lambda i: abs(times[i] - 4e-5))
    um = {k: [v * 1e6 for v in pool[k].tolist()] for k in
          ("length", "width", "depth", "width_solidus_substrate", "depth_solidus_substrate")}
    at = {k: v[i_at] for k, v in um.items()}
    big = {k: max(v) for k, v in um.items()}
    beads = run.track_bead()
    bead = {k: v.tolist()[-1] * 1e6 for k, v in beads.items()}
    wk = [k for k in beads if k.startswith("width_")][0]
    hk = "height_" + wk[len("width_"):]
    cd = run.probe_line("CD", 2)
    end = run.probe_line("CD", len(beads["time"]) - 1)
    MPa = lambda t, k: [v * 1e-6 for v in t[k].tolist()]
    print("| %d W | %.0f x %.0f x %.0f | %.0f x %.0f x %.0f | %.0f x %.0f | %.0f x %.0f, %.0f x %.0f "
          "| %.0f, %.0f, %.0f, %.1f %% | %.0f / %.0f, %.0f |"
          % (p, at["length"], at["width"], at["depth"],
             big["length"], big["width"], big["depth"],
             big["width_solidus_substrate"], big["depth_solidus_substrate"],
             bead[wk], bead[hk], bead["centre_length"], bead["centre_height"],
             max(cd["T"].tolist()), max(MPa(cd, "sigma_xx"), key=abs),
             max(MPa(cd, "von_mises")), 100 * max(cd["plastic_strain"].tolist()),
             min(MPa(end, "sigma_xx")), max(MPa(end, "sigma_xx")), max(MPa(end, "von_mises"))))
PY
