#!/usr/bin/env bash
# Run femp's benchmarks on one core (Release build) and print the figures
# quoted in doc/performance.md. Usage: contrib/run_benchmarks.sh [build-dir]
set -euo pipefail
build=${1:-build}
cmake --build "$build" --target bench_thermal femp -j2 > /dev/null
echo "== thermal step and point bookkeeping (case 3.2 grid, 624k cells, 2.3M points)"
taskset -c 0 "$build/contrib/bench_thermal" 7
echo "== default scene, 1 rank (timer summary)"
(cd "$build" && taskset -c 0 ./femp ../prm/single_track.prm | tail -16)
