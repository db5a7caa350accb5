#!/usr/bin/env bash
# The installed tool, run as a user would: from PATH, in a folder outside the source and build
# trees. It simulates and replays with the project's hand and objects from PREFIX/share/inhand,
# evaluate draws its plots with the installed plotting module, and the installed Python module
# simulates too; with an object removed from that folder both say
# which file they miss there.
# usage: check_command.sh BUILD_DIR WORK_DIR PYTHON PYTHON_INSTALL_DIR (the last two may be "")
set -euo pipefail
build=$1 work=$2 python=$3 pydir=$4
rm -rf "$work" && mkdir -p "$work/run"
prefix="$work/prefix"
cmake --install "$build" --prefix "$prefix" > "$work/install.log"
cd "$work/run"
export PATH="$prefix/bin:$PATH"
[ "$(command -v inhand)" = "$prefix/bin/inhand" ] || { echo "FAIL: inhand on PATH is $(command -v inhand)"; exit 1; }
inhand simulate pen-fingertip --no-images --out session > simulate.log
inhand replay session --modalities j,jt --no-video --out replay > replay.log
grep -q '"jt"' replay/summary.json || { echo "FAIL: replay/summary.json has no jt"; exit 1; }
if [ -n "$python" ]; then  # evaluate finds the installed plotting module
  inhand evaluate --out eval --seeds 1 --scenarios pen-fingertip --modalities j > evaluate.log 2>&1 \
    || { cat evaluate.log; exit 1; }
  [ -s eval/fig7_pen-fingertip.svg ] && [ -s eval/terminal_errors.pdf ] \
    || { echo "FAIL: the installed evaluate drew no plots:"; cat evaluate.log; exit 1; }
fi
# The installed assets are the ones read: without the pen there, the pen cannot be simulated.
mv "$prefix/share/inhand/assets/objects/pen" "$work/pen"
missing="$prefix/share/inhand/assets/objects/pen/object.json"
if inhand simulate pen-fingertip --no-images --out session2 2> error.txt; then
  echo "FAIL: simulated the pen without its installed description"; exit 1
fi
grep -qF "$missing" error.txt || { echo "FAIL: the error does not name $missing:"; cat error.txt; exit 1; }
if [ -n "$python" ]; then
  PYTHONPATH="$prefix/$pydir" PYTHONDONTWRITEBYTECODE=1 "$python" - "$prefix" "$missing" <<'PY'
import sys
import inhand
prefix, missing = sys.argv[1], sys.argv[2]
assert inhand.__file__.startswith(prefix + "/"), inhand.__file__
try:
    inhand.simulate("pen-fingertip", "session3", images=False)
    sys.exit("FAIL: the installed module simulated the pen without its installed description")
except inhand.InputError as e:
    assert missing in str(e), str(e)
print(inhand.simulate("ketchup-power-grasp", "session4", images=False)["joint_samples"], "samples")
PY
fi
echo "installed inhand simulated and replayed from $prefix"
