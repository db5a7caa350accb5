#!/usr/bin/env bash
# The main job (make demo): simulate the paper's first experiment (ketchup-power-grasp) and
# replay it with the estimators into OUT: estimates, summary and the annotated video.
# Everything is written to a temporary folder first and moved into place only when complete.
set -euo pipefail
INHAND=${1:-build/bin/inhand}
OUT=${2:-out/demo}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
TMP="${OUT%/}.tmp-$$"
rm -rf "$TMP"
mkdir -p "$TMP"
trap 'rm -rf "$TMP"' EXIT

echo "== the project's hand"
"$INHAND" model "$ROOT/assets/hands/inhand_hand/inhand_hand.urdf" --render "$TMP/hand.png" > "$TMP/hand.txt"
echo "   summary in hand.txt, preview in hand.png"
echo "== simulate ketchup-power-grasp (seed 1, paper noise)"
"$INHAND" simulate ketchup-power-grasp --out "$TMP/session" --seed 1 --noise paper
echo "== replay"
"$INHAND" replay "$TMP/session" --out "$TMP/replay"

rm -rf "$OUT"
mkdir -p "$(dirname "$OUT")"
mv "$TMP" "$OUT"
trap - EXIT
echo "demo written to $OUT: replay/replay.mp4 (annotated video), replay/summary.json, replay/estimates.csv, session/"
