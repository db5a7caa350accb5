#!/usr/bin/env bash
# Runs the benchmarks with repetitions; prints medians (machines are noisy: read the median).
set -euo pipefail
BUILD=${1:-build}
"$BUILD/bin/inhand_bench" --benchmark_repetitions=10 --benchmark_report_aggregates_only=true \
  --benchmark_display_aggregates_only=true "${@:2}"
# The Python module's cost per sample over the C++ step (built with INHAND_BUILD_PYTHON).
if [[ -x "$BUILD/bin/inhand_bench_python" ]]; then
  "$BUILD/bin/inhand_bench_python" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
    --benchmark_display_aggregates_only=true
fi
