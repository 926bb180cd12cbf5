#!/usr/bin/env bash
# The dependency rule (docs/development.md), checked: every #include of a fralab header in a
# module's library (include/ and src/) must name a module the rule allows; executables (app/) and
# the LCM edges (*/lcm/) may also use the LCM bridge. Prints each violation as FILE:LINE: what, and
# exits 1 when there is any. Usage: check_layering.sh [SOURCE_DIR]
set -uo pipefail
root=${1:-$(cd "$(dirname "$0")/.." && pwd)}
cd "$root" || exit 2

# Modules a module's library may include (itself included). "lcm" is the LCM bridge: fralab/lcm_io.h,
# the generated fralab/*_t.hpp and <lcm/...>.
declare -A allowed=(
  [core]="core"
  [lcmtypes]="core lcm"
  [plant]="core plant"
  [acquire]="core plant analyze acquire"
  [analyze]="core analyze"
  [identify]="core analyze identify"
  [diagnose]="core plant analyze identify diagnose"
  [exchange]="core plant analyze identify exchange"
  [envelope]="core plant analyze identify diagnose exchange envelope"
  [lab]="core lcm plant acquire analyze identify diagnose exchange envelope lab"
)

module_of_include() {  # the module an include names, or "" for a non-fralab header
  case "$1" in
    '<lcm/'* | *'fralab/lcm_io.h'* | *'fralab/'*'_t.hpp'*) echo lcm ;;
    *'"tape_analysis.h"'*) echo lcm ;;  # analyze/lcm: the analyser's LCM edge
    *'fralab/core/'*) echo core ;;
    *'fralab/plant/'*) echo plant ;;
    *'fralab/acquire/'*) echo acquire ;;
    *'fralab/analyze/'*) echo analyze ;;
    *'fralab/identify/'*) echo identify ;;
    *'fralab/diagnose/'*) echo diagnose ;;
    *'fralab/exchange/'*) echo exchange ;;
    *'fralab/envelope/'*) echo envelope ;;
    *'fralab/lab/'*) echo lab ;;
    *) echo "" ;;
  esac
}

bad=0
for mod in "${!allowed[@]}"; do
  [ -d "$mod" ] || { echo "check_layering: module folder $mod/ missing" >&2; bad=1; continue; }
  while IFS= read -r file; do
    # Executables and the LCM edges may use the bridge on top of what their module may use.
    extra=""
    case "$file" in */app/* | */lcm/*) extra="lcm" ;; esac
    while IFS=: read -r line text; do
      target=$(module_of_include "$text")
      [ -z "$target" ] && continue
      ok=0
      for a in ${allowed[$mod]} $extra; do [ "$a" = "$target" ] && ok=1; done
      if [ $ok = 0 ]; then
        echo "$file:$line: $mod may not include $target (${text#\#include })"
        bad=1
      fi
    done < <(grep -n '^#include' "$file")
  done < <(find "$mod" -name '*.h' -o -name '*.cc' -o -name '*.hpp' | sort)
done
# Executables are thin: no module's app/ is included by anyone.
if grep -rn --include='*.h' --include='*.cc' '#include ".*app/' . 2>/dev/null | grep -v '^./build'; then
  bad=1
fi
if [ $bad = 0 ]; then echo "check_layering: every include follows the dependency rule"; fi
exit $bad
