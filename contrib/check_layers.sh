#!/usr/bin/env bash
# Checks that no include of femp runs back up the layers of the source tree:
#   base -> grid -> heat | flow | solid -> coupling -> io -> builds -> app
# A file in include/femp/<group>/ or source/<group>/ may include femp
# headers of its own group and of the groups below it; heat, flow and solid
# are siblings and do not include each other. Exits non-zero and lists every
# include that breaks the rule. Run by ctest (test 'include_layers').
set -euo pipefail
cd "$(dirname "$0")/.."
rank() {
  case "$1" in
    base) echo 0 ;;
    grid) echo 1 ;;
    heat | flow | solid) echo 2 ;;
    coupling) echo 3 ;;
    io) echo 4 ;;
    builds) echo 5 ;;
    app) echo 6 ;;
    *) echo -1 ;;
  esac
}
bad=0
n=0
while IFS= read -r f; do
  g=${f#include/femp/}
  g=${g#source/}
  g=${g%%/*}
  rg=$(rank "$g")
  if [ "$rg" -lt 0 ]; then
    echo "unknown group '$g' of $f (add it to contrib/check_layers.sh)"
    bad=1
    continue
  fi
  while IFS= read -r h; do
    n=$((n + 1))
    rh=$(rank "$h")
    if [ "$rh" -lt 0 ] || [ "$rh" -gt "$rg" ] || { [ "$rh" -eq "$rg" ] && [ "$h" != "$g" ]; }; then
      echo "$f includes femp/$h/ (group $g may include only its own group and those below it)"
      bad=1
    fi
  done < <(sed -n 's|^[[:space:]]*#[[:space:]]*include[[:space:]]*[<"]femp/\([a-z_]*\)/.*|\1|p' "$f")
done < <(find include/femp source -name '*.h' -o -name '*.cc' | sort)
if [ "$bad" -ne 0 ]; then
  echo "layers: base -> grid -> heat | flow | solid -> coupling -> io -> builds -> app"
  exit 1
fi
echo "no include runs back up the layers ($n femp includes checked)"
