#!/usr/bin/env bash
# A user's project (app/examples) configured against the installed tree with find_package,
# built and run on a simulated session; its tracker's last pose equals `inhand replay`'s.
# usage: check_example.sh PREFIX SOURCE_DIR INHAND_BINARY WORK_DIR
set -euo pipefail
prefix=$1 src=$2 inhand=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
cmake -S "$src/app/examples" -B "$work/build" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" > "$work/configure.log" \
  || { cat "$work/configure.log"; exit 1; }
cmake --build "$work/build" > "$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }
"$inhand" simulate ketchup-power-grasp --seed 3 --noise paper --out "$work/session" > /dev/null
"$work/build/track_session" "$work/session" jta > "$work/poses.txt"
frames=$(grep -c '^frame ' "$work/poses.txt")
expected=$(($(wc -l < "$work/session/camera.csv") - 1))
[ "$frames" -eq "$expected" ] || { echo "FAIL: $frames pose lines for $expected camera frames"; exit 1; }
"$inhand" replay "$work/session" --out "$work/replay" --modalities jta --no-video > /dev/null
# The last jta row of estimates.csv against the example's last line (9 decimals printed).
python3 - "$work/poses.txt" "$work/replay/estimates.csv" <<'PY'
import csv, sys
last = [l.split() for l in open(sys.argv[1]) if l.startswith('last ')][0]
rows = [r for r in csv.DictReader(open(sys.argv[2])) if r['set'] == 'jta']
ref = rows[-1]
mine = [float(v) for v in last[2:9]]
theirs = [float(ref[k]) for k in ('px', 'py', 'pz', 'qw', 'qx', 'qy', 'qz')]
worst = max(abs(a - b) for a, b in zip(mine, theirs))
sign = -1 if theirs[3] * mine[3] < 0 else 1  # q and -q are one rotation
worst = min(worst, max(abs(a - b) for a, b in zip(mine[:3] + [sign * v for v in mine[3:]], theirs)))
print(f"example's last pose vs replay's: {worst:.2e}")
sys.exit(0 if worst < 2e-9 else 1)
PY
echo "installed example: configured with find_package, built, $frames frames tracked"
