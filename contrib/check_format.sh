#!/usr/bin/env bash
# Checks that every tracked C++ file follows .clang-format (clang-format 14,
# Debian 12's). Exits non-zero and lists the files that do not; fix them with
#   clang-format -i $(git ls-files '*.cc' '*.h')
set -euo pipefail
cd "$(dirname "$0")/.."
bad=0
for f in $(git ls-files '*.cc' '*.h'); do
  if ! clang-format --dry-run --Werror "$f" >/dev/null 2>&1; then
    echo "not formatted: $f"
    bad=1
  fi
done
if [ "$bad" -ne 0 ]; then
  echo "run: clang-format -i \$(git ls-files '*.cc' '*.h')"
  exit 1
fi
echo "all C++ files follow .clang-format"
