#!/usr/bin/env bash
# Figures for docs/validation.md: the engine time the lab's campaign takes against the bound, the
# engine time the best sine would need to size every finding's parameters as well (`fralab bound`,
# docs/method/engine-time-bound.md), on the J85 at 70, 85 and 95 % (each diagnosed against its
# _sim by `fralab diagnose --engine`, the auto campaign and its validation run). Per operating
# point: findings, the campaign's engine time, its validation's, the bound, their ratio and the
# parameter that sets the bound; then the median of every parameter's own ratio. Run after
# scripts/build.sh (about 1.5 min on two idle cores):
#   bash bench/engine_time.sh [OUT [DIAGNOSE FLAGS...]]     # e.g. OUT --excitation stepped
set -euo pipefail
cd "$(dirname "$0")/.."
B=${FRALAB_BIN:-build/bin}
out=${1:-$(mktemp -d)}
shift || true
mkdir -p "$out"
for op in 70 85 95; do
  scripts/isolated.sh $B/fralab diagnose --engine j85_$op --simulation j85_${op}_sim --no-plots \
    --no-progress --out "$out/j85_$op" "$@" > "$out/j85_$op.log"
  $B/fralab bound --simulation j85_${op}_sim --diagnosis "$out/j85_$op" \
    --json "$out/j85_$op/bound.json" > "$out/j85_$op/bound.txt"
done
/usr/bin/python3 - "$out" <<'PY'
import json, statistics, sys
out = sys.argv[1]
print("%-7s %8s %12s %13s %9s %7s  %s" % ("point", "findings", "campaign s", "validation s",
                                           "bound s", "ratio", "the bound's parameter"))
ratios = []
for op in (70, 85, 95):
    b = json.load(open(f"{out}/j85_{op}/bound.json"))
    d = json.load(open(f"{out}/j85_{op}/diagnosis.json"))
    ps = b["parameters"]
    ratios += [p["ratio"] for p in ps]
    hard = max(ps, key=lambda p: p["bound_s"]) if ps else None
    what = (f"{hard['cause']} [{hard['scope']} {hard['input']} {hard['output']}] "
            f"{hard['parameter']}, best sine {hard['best_input']} at "
            f"{hard['best_w_rad_s']:.3g} rad/s") if hard else "-"
    print("%-7s %8d %12.1f %13.1f %9.1f %7.2f  %s" % (f"{op} %", len(d["findings"]),
          b["campaign_s"], b["validation_s"], b["bound_s"], b["ratio"], what))
if ratios:
    print("every parameter's own ratio: median %.3g (min %.3g, max %.3g, %d parameters)" % (
        statistics.median(ratios), min(ratios), max(ratios), len(ratios)))
PY
