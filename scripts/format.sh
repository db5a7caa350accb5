#!/usr/bin/env bash
# The house style (.clang-format: Google's, 100 columns) over every C++ file git tracks, and the
# new ones it does not ignore (a file formatted only once added is a red CI).
#   scripts/format.sh           formats them in place
#   scripts/format.sh --check   changes nothing; lists the files that differ and exits 1 (CI)
set -euo pipefail
cd "$(dirname "$0")/.."
mapfile -t files < <(git ls-files --cached --others --exclude-standard '*.cpp' '*.hpp' '*.h' | grep -v '/node_modules/')
if [ "${1:-}" = "--check" ]; then
  bad=()
  for f in "${files[@]}"; do
    clang-format --dry-run -Werror "$f" > /dev/null 2>&1 || bad+=("$f")
  done
  if [ ${#bad[@]} -gt 0 ]; then
    printf 'not formatted (scripts/format.sh fixes it): %s\n' "${bad[@]}" >&2
    exit 1
  fi
  echo "format: ${#files[@]} files as .clang-format says"
else
  clang-format -i "${files[@]}"
fi
