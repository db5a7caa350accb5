#!/usr/bin/env bash
# Runs the benchmarks with repetitions; prints medians (machines are noisy: read the median).
set -euo pipefail
BUILD=${1:-build}
"$BUILD/bin/inhand_bench" --benchmark_repetitions=10 --benchmark_report_aggregates_only=true \
  --benchmark_display_aggregates_only=true "${@:2}"
