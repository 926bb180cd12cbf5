#!/usr/bin/env bash
# Figures for docs/validation.md: the auto campaign (orthogonal multisine, a sine for the actuators
# that distort) and the orthogonal multisine alone (2 periods; its backlash fitted by its best
# linear approximation) against the report's stepped sine, on the J85 at 70, 85 and 95 % (each
# against its _sim), same seed. Per operating point and campaign: engine time, findings, error,
# validation error on its own validation run, and both extended models' error on the same data
# (the stepped run's validation measurement). Run after scripts/build.sh (about 15 min, the
# stepped runs most):
#   bash bench/campaign_compare.sh [SEED]
set -euo pipefail
cd "$(dirname "$0")/.."
B=${FRALAB_BIN:-build/bin}
seed=${1:-1}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
summary() {  # DIR -> "engine_s findings error validation"
  /usr/bin/python3 - "$1" <<'PY'
import json, sys
d = sys.argv[1]
j = json.load(open(d + "/diagnosis.json"))
r = json.load(open(d + "/measure/run.json"))
s = j["summary"]
print("%.0f %d %.4f %.4f" % (r["engine_time_s"], len(j["findings"]), s["error_after"],
                             s["validation_error_after"]))
PY
}
findings() {
  /usr/bin/python3 - "$1" <<'PY'
import json, sys
j = json.load(open(sys.argv[1] + "/diagnosis.json"))
print("; ".join(sorted("%s %s %s %s" % (f["cause"], f["input"], f["output"] or "",
      ",".join("%s=%.3g" % (k, v) for k, v in f["parameters"].items() if isinstance(v, float)))
      for f in j["findings"])))
PY
}
echo "| point | campaign | engine s | findings | error | validation (own) | on the stepped validation data |"
echo "|---|---|---|---|---|---|---|"
for op in 70 85 95; do
  for c in stepped auto multisine; do
    extra=()
    [ "$c" = multisine ] && extra=(--min-cycles 2)
    scripts/isolated.sh $B/fralab diagnose --simulation j85_${op}_sim --engine j85_$op \
      --excitation $c "${extra[@]}" --seed "$seed" --no-plots --no-progress \
      --out "$out/$op/$c" > /dev/null
  done
  for c in stepped auto multisine; do
    $B/fralab diagnose --simulation "$out/$op/$c/extended_model.json" --no-plots \
      --measured "$out/$op/stepped/measure/validation" --out "$out/$op/x_$c" > /dev/null
    read -r eng n err val <<< "$(summary "$out/$op/$c")"
    cross=$(/usr/bin/python3 -c "import json; print('%.4f' % json.load(open('$out/$op/x_$c/diagnosis.json'))['summary']['error_before'])")
    echo "| ${op} % | $c | $eng | $n | $err | $val | $cross |"
  done
  for c in auto multisine; do
    if [ "$(findings "$out/$op/stepped" | sed 's/=[^ ;,]*//g')" = "$(findings "$out/$op/$c" | sed 's/=[^ ;,]*//g')" ]; then
      echo "  ${op} % $c: the stepped run's findings: $(findings "$out/$op/$c")" >&2
    else
      echo "  ${op} % $c: findings differ: stepped: $(findings "$out/$op/stepped") / $c: $(findings "$out/$op/$c")" >&2
    fi
  done
done
