#!/usr/bin/env bash
# One run per output folder, and feedback from a long run (doc/input_errors.md,
# "One run per output folder", "Progress"):
#  1. a run into a folder whose lock names a live process is refused, naming
#     its pid, host and start time, and writes nothing there (1 and 2 ranks;
#     on 2 ranks without MPI_Abort);
#  2. a long run prints 'femp: still working' when it has printed nothing for
#     'Run limits/Progress wall interval' (0.5 s here);
#  3. a second run started into the folder of a running one is refused,
#     naming the first run's pid;
#  4. the first run killed by SIGTERM leaves a stale lock: a resume from its
#     checkpoint takes it over with a note and completes; the lock is gone at
#     the end;
#  5. a resume into a folder locked by a live run is refused.
# Usage: output_lock.sh FEMP SCENE WORKDIR MPIEXEC [MPIFLAGS...]
set -u
femp=$1 scene=$2 work=$3 mpiexec=$4
shift 4
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
host=$(hostname)
fail() { echo "FAILED: $*"; [ -n "${first:-}" ] && kill -9 "$first" 2>/dev/null; exit 1; }
short=(--set "Time stepping/End time=1e-6" --set "Output/Write material points=never")

# 1. A lock naming this script (alive), on 1 and 2 ranks.
mkdir -p live
printf 'pid %s\nhost %s\nstart 2026-01-01 00:00:00 UTC\n' $$ "$host" > live/femp.lock
out=$("$femp" "${short[@]}" --set Output/Directory=live "$scene" 2>&1) &&
  fail "a locked folder was accepted: $out"
echo "$out" | grep -q "Output/Directory.*another run of femp writes into this folder (pid $$ on host $host, started 2026-01-01 00:00:00 UTC" ||
  fail "1 rank: unexpected message: $out"
out=$("$mpiexec" "$@" -np 2 "$femp" "${short[@]}" --set Output/Directory=live "$scene" 2>&1) &&
  fail "2 ranks: a locked folder was accepted: $out"
echo "$out" | grep -q "another run of femp writes into this folder (pid $$" ||
  fail "2 ranks: unexpected message: $out"
echo "$out" | grep -q "MPI_ABORT" && fail "2 ranks: the refusal used MPI_Abort: $out"
[ "$(ls live)" = "femp.lock" ] || fail "files were written into the locked folder: $(ls live)"
grep -q "pid $$" live/femp.lock || fail "the other run's lock was changed"
echo "1. locked folder refused (1 and 2 ranks), nothing written"

# 2. + 3. A long run; a second one into its folder.
"$femp" --set Output/Directory=both --set "Time stepping/End time=1" \
  --set "Output/Write material points=never" --set "Output/Progress interval=100000000" \
  --set "Output/Output interval=1" --set "Checkpoint/Every steps=50" \
  --set "Run limits/Progress wall interval=0.5" "$scene" > first.log 2>&1 &
first=$!
for i in $(seq 1 300); do
  [ -d both/checkpoint ] && grep -q "still working" first.log && break
  sleep 0.1
done
kill -0 $first 2>/dev/null || fail "the first run ended early: $(cat first.log)"
grep -q "femp: still working: .*simulated time .* step .*wall" first.log ||
  fail "no 'still working' line after 30 s: $(cat first.log)"
echo "2. a long run without progress lines prints 'femp: still working'"
out=$("$femp" "${short[@]}" --set Output/Directory=both "$scene" 2>&1) &&
  fail "a second run into a running one's folder was accepted: $out"
echo "$out" | grep -q "another run of femp writes into this folder (pid $first on host $host" ||
  fail "second run: unexpected message: $out"
kill -0 $first 2>/dev/null || fail "the first run was disturbed: $(cat first.log)"
echo "3. a second run into the folder of a running one is refused"

# 4. SIGTERM leaves a stale lock; a resume takes it over.
kill -TERM $first
wait $first
first=
grep -q "pid" both/femp.lock || fail "no lock left by the killed run"
out=$("$femp" --resume both/checkpoint --set Output/Directory=both \
  --set "Time stepping/End time=$(awk '/^Checkpoint: step/ {t = $5} END {print t + 2e-4}' first.log)" \
  --set "Output/Write material points=never" --set "Output/Output interval=1" \
  --set "Checkpoint/Every steps=50" "$scene" 2>&1)
rc=$?
echo "$out" | grep -q "femp: note: taking over the lock of 'both' left by an earlier run that is gone (pid [0-9]* on host $host" ||
  fail "resume: no note about the stale lock (exit $rc): $out"
[ $rc -eq 0 ] || fail "resume after a stale lock failed: $out"
[ -e both/femp.lock ] && fail "the lock was left after the run"
echo "4. a stale lock is taken over with a note; the resumed run removes it"

# 5. A resume into a folder locked by a live run.
printf 'pid %s\nhost %s\nstart 2026-01-01 00:00:00 UTC\n' $$ "$host" > both/femp.lock
out=$("$femp" --resume both/checkpoint --set Output/Directory=both "$scene" 2>&1) &&
  fail "a resume into a locked folder was accepted: $out"
echo "$out" | grep -q "another run of femp writes into this folder (pid $$" ||
  fail "resume: unexpected message: $out"
echo "5. a resume into a locked folder is refused"
