#!/usr/bin/env bash
# The main job (make demo): what the project can do end to end today, written into OUT.
# Output goes to a temporary folder first and is moved into place only when complete.
set -euo pipefail
INHAND=${1:-build/bin/inhand}
OUT=${2:-out/demo}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
TMP="${OUT%/}.tmp-$$"
rm -rf "$TMP"
mkdir -p "$TMP"
trap 'rm -rf "$TMP"' EXIT

echo "== the project's hand"
"$INHAND" model "$ROOT/assets/hands/inhand_hand/inhand_hand.urdf" | tee "$TMP/hand.txt"
"$INHAND" model "$ROOT/assets/hands/inhand_hand/inhand_hand.urdf" --json > "$TMP/hand.json"
for object in "$ROOT"/assets/objects/*/object.json; do
  name=$(basename "$(dirname "$object")")
  echo "== object $name"
  "$INHAND" model "$object" | tee "$TMP/object_$name.txt"
  "$INHAND" model "$object" --json > "$TMP/object_$name.json"
done

rm -rf "$OUT"
mkdir -p "$(dirname "$OUT")"
mv "$TMP" "$OUT"
trap - EXIT
echo "demo written to $OUT"
