#!/usr/bin/env bash
# Figures for docs/validation.md: the J85 across its envelope (70, 85, 95 % N/Nmax), measured and
# diagnosed by `fralab envelope` with every input (the auto campaign at each point, measured once):
# wall and engine time, the findings across points with their laws, leave-one-out at 85 % (the
# scheduled extended model from 70 and 95 % against the 85 % measurement, beside 85 %'s
# simulation and own extended model, and the bounds: at most twice the own model's error and a
# third of the simulation's), and the scheduled model measured at 90 %. Run after
# scripts/build.sh (about 1 min on two idle cores):
#   bash bench/envelope.sh [OUT [ENVELOPE FLAGS...]]     # e.g. OUT --validation
set -euo pipefail
cd "$(dirname "$0")/.."
B=${FRALAB_BIN:-build/bin}
out=${1:-$(mktemp -d)}
shift || true
mkdir -p "$out"
start=$(date +%s)
scripts/isolated.sh $B/fralab envelope --engine j85 --simulation j85_sim --no-progress \
  --out "$out/envelope" "$@" > "$out/envelope.log"
wall=$(($(date +%s) - start))
scripts/isolated.sh $B/fralab measure --engine "$out/envelope/scheduled_model.json@90" \
  --excitation auto --no-progress --out "$out/at90" > /dev/null
/usr/bin/python3 - "$out" "$wall" <<'PY'
import glob, json, sys
out, wall = sys.argv[1], int(sys.argv[2])
env = json.load(open(f"{out}/envelope/envelope.json"))
engine = 0.0
for run in glob.glob(f"{out}/envelope/*/measure/run.json") + \
           glob.glob(f"{out}/envelope/*/measure/validation/run.json"):
    engine += json.load(open(run)).get("engine_time_s", 0.0)
print(f"wall {wall} s, engine {engine:.0f} s ({engine / 60:.1f} min)")
for f in env["findings"]:
    print("-", f["text"])
ok = True
for l in env["leave_one_out"]:
    if "refused" in l:
        print(f"leave-one-out at {l['point']}: refused: {l['refused']}")
        ok = False
        continue
    s, m, e = l["error_simulation"], l["error_scheduled"], l["error_extended"]
    within = m <= 2 * e and m <= s / 3
    ok = ok and within
    print(f"leave-one-out at {l['point']}: simulation {s:.4f}, scheduled {m:.4f}, "
          f"own extended {e:.4f}: {m / e:.2f} x own, {s / m:.1f} x below the simulation "
          f"({'within' if within else 'NOT within'} 2 x own and 1/3 of the simulation)")
eng = json.load(open(f"{out}/at90/engine.json"))
for i in eng["inputs"]:
    if i["name"] == "A8":
        p = i["actuator"]["tf"]["poles"][0]
        print(f"at 90 %: the A8 actuator {p.get('wn', -p.get('real', 0)):.2f} rad/s")
sys.exit(0 if ok else 1)
PY
