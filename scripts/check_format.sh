#!/usr/bin/env bash
# The sources follow .clang-format: every C++ file git tracks (and every one it does not yet track
# but would) is checked with clang-format --dry-run; prints each file that differs and exits 1 when
# there is any (2 when clang-format is missing). Usage: check_format.sh [SOURCE_DIR]
set -uo pipefail
root=${1:-$(cd "$(dirname "$0")/.." && pwd)}
cd "$root" || exit 2
command -v clang-format >/dev/null || { echo "check_format: clang-format is not installed"; exit 2; }
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files --cached --others --exclude-standard -- \
    '*.cc' '*.h' '*.cpp' '*.hpp')
else
  mapfile -t files < <(find . -path ./build -prune -o -path ./build-fuzz -prune -o \
    \( -name '*.cc' -o -name '*.h' \) -print)
fi
bad=0
for f in "${files[@]}"; do
  [ -f "$f" ] || continue
  if ! clang-format --dry-run --Werror "$f" >/dev/null 2>&1; then
    echo "$f: not clang-format clean (clang-format -i $f)"
    bad=1
  fi
done
echo "check_format: ${#files[@]} files, $([ $bad -eq 0 ] && echo clean || echo "some differ")"
exit $bad
