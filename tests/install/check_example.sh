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
awk -F, -v poses="$work/poses.txt" '
  BEGIN { while ((getline line < poses) > 0) if (line ~ /^last /) split(line, mine, " ") }
  NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
  $col["set"] == "jta" { for (k = 0; k < 7; ++k) ref[k] = $(col["px"] + k) }
  END {
    sign = (ref[3] * mine[6] < 0) ? -1 : 1  # q and -q are one rotation
    worst = 0
    for (k = 0; k < 7; ++k) {
      d = mine[3 + k] * (k >= 3 ? sign : 1) - ref[k]
      if (d < 0) d = -d
      if (d > worst) worst = d
    }
    printf "example'"'"'s last pose vs replay'"'"'s: %.2e\n", worst
    exit (worst < 2e-9 ? 0 : 1)
  }' "$work/replay/estimates.csv"
echo "installed example: configured with find_package, built, $frames frames tracked"
