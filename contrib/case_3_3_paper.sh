#!/bin/bash
# The paper's case 3.3 at the paper's scale: the single track at 50, 100
# and 200 W with the fast FEMP scene prm/case_3_2_femp_fast.prm (4 um grid,
# 2 um points, the paper's domain), each to 0.3 ms, the time of the paper's
# Figs 9-10 (doc/cases.md "Case 3.3 at the paper's scale"). About half an
# hour per power on 2 cores.
#
#   contrib/case_3_3_paper.sh [NPROC] [OUTPUT_ROOT] [FIGURE_DIR]
#
# (defaults 2, output/case_3_3_paper, doc/figures), run from the repository
# root with build/femp built. Writes OUTPUT_ROOT/{50W,100W,200W} (field
# output every 0.1 ms: number 3 is t = 0.3 ms), the figure
#   FIGURE_DIR/case_3_3_paper_power.svg  T, sigma_xx and von Mises on CD
#       and sigma_xx on EF at 0.3 ms for the three powers,
# and prints the table of pool size, bead size and stresses against the
# power (contrib/track_power_table.py). MPIRUN overrides the MPI launcher
# (default: mpirun); NO_RUN=1 only redraws the figure and the table from
# existing output; POWERS="50 100" runs a subset. A run that exists
# (probe_line_CD_00003.csv written) is not repeated.
set -e
NP=${1:-2}
ROOT=${2:-output/case_3_3_paper}
FIG=${3:-doc/figures}
MPIRUN=${MPIRUN:-mpirun}
POWERS=${POWERS:-50 100 200}
mkdir -p "$ROOT" "$FIG"

if [ -z "$NO_RUN" ]; then
  for P in $POWERS; do
    dir="$ROOT/${P}W"
    if [ -f "$dir/probe_line_CD_00003.csv" ]; then
      echo "== $dir: done"
      continue
    fi
    echo "== $dir"
    $MPIRUN -np "$NP" build/femp --set "Laser/Power=$P" \
      --set "Time stepping/End time=3e-4" \
      --set "Output/Directory=$dir" \
      prm/case_3_2_femp_fast.prm > "$dir.log" 2>&1 || { tail -20 "$dir.log"; exit 1; }
    tail -1 "$dir.log"
  done
fi

python3 contrib/plot_track_svg.py --compare "$FIG/case_3_3_paper_power.svg" --n 3 \
  "$ROOT/50W=50 W" "$ROOT/100W=100 W" "$ROOT/200W=200 W" \
  CD:T CD:sigma_xx CD:von_mises EF:sigma_xx
python3 contrib/track_power_table.py --n 3 \
  "$ROOT/50W=50 W" "$ROOT/100W=100 W" "$ROOT/200W=200 W"
