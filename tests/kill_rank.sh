#!/usr/bin/env bash
# A rank killed by SIGKILL in the middle of a run must leave every index file
# valid: each file that grid.pvd / points.pvd (and any .xdmf) lists exists and
# is complete, and so is every piece a listed .pvtu names.
# Usage: kill_rank.sh FEMP SCENE WORKDIR MPIEXEC [MPIFLAGS...]
set -u
femp=$1 scene=$2 work=$3 mpiexec=$4
shift 4
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
"$mpiexec" "$@" -np 2 "$femp" --set "Output/Directory=$work/out" \
  --set "Time stepping/End time=1" --set "Output/Steps between outputs=2" \
  --set "Output/Write material points=always" "$scene" > run.log 2>&1 &
launcher=$!
# Wait until a few outputs are listed, then kill the last rank started.
for i in $(seq 1 600); do
  n=$(grep -c '<DataSet' out/grid.pvd 2>/dev/null || echo 0)
  [ "$n" -ge 6 ] && break
  sleep 0.2
done
ranks=$(pgrep -P $launcher)
if [ -z "$ranks" ] || [ "${n:-0}" -lt 6 ]; then
  echo "FAILED: the run did not write 6 outputs in 120 s"; kill -9 $launcher $ranks 2>/dev/null; exit 1
fi
kill -9 $(echo "$ranks" | tail -1)
wait $launcher
rc=$?
echo "launcher exit code after SIGKILL of one rank: $([ $rc -ne 0 ] && echo non-zero || echo 0)"
[ $rc -ne 0 ] || { echo "FAILED: the run was not killed"; exit 1; }

bad=0 listed=0
complete() { # a VTK XML or XDMF file is complete when it ends with its closing tag
  [ -f "$1" ] && tail -c 200 "$1" | grep -q -e '</VTKFile>' -e '</Xdmf>'
}
for index in out/*.pvd out/*.xdmf; do
  [ -f "$index" ] || continue
  complete "$index" || { echo "FAILED: $index is incomplete"; bad=$((bad+1)); }
  for f in $(grep -o 'file="[^"]*"' "$index" | sed 's/file="//;s/"$//'); do
    listed=$((listed+1))
    complete "out/$f" || { echo "FAILED: $index lists $f, which is missing or incomplete"; bad=$((bad+1)); continue; }
    case $f in *.pvtu)
      for p in $(grep -o 'Source="[^"]*"' "out/$f" | sed 's/Source="//;s/"$//'); do
        complete "out/$p" || { echo "FAILED: $f names piece $p, which is missing or incomplete"; bad=$((bad+1)); }
      done;;
    esac
  done
done
echo "files listed by the indices: $([ $listed -ge 12 ] && echo 'at least 12' || echo "$listed")"
echo "missing or incomplete: $bad"
[ $bad -eq 0 ] && [ $listed -ge 12 ]
