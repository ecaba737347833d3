#!/usr/bin/env bash
# make bench-real: scripts/bench_real.py over the build's skelcd and dcd_vs_cgal (docs/benchmarks.md
# "Real assets"). Usage: scripts/bench_real.sh [BUILD] [bench_real.py options…]
set -euo pipefail
build=${1:-build}
shift || true
here=$(cd "$(dirname "$0")" && pwd)
exec /usr/bin/python3 "$here/bench_real.py" --skelcd "$build/tools/skelcd" \
  --dcd "$build/bench/real/dcd_vs_cgal" "$@"
