#!/usr/bin/env bash
# make bench-real: scripts/bench_real.py over the build's skelcd and dcd_vs_cgal (docs/benchmarks.md
# "Real assets"). Usage: scripts/bench_real.sh [BUILD] [bench_real.py options…]
set -euo pipefail
build=${1:-build}
shift || true
here=$(cd "$(dirname "$0")" && pwd)
# What is measured is what the sources say: dcd_vs_cgal is outside the default target, and an
# old one would go on measuring the DCD of its day. Its target exists only with libcgal-dev.
if [[ -f "$build/build.ninja" || -f "$build/Makefile" ]]; then
  cmake --build "$build" --target skelcd >&2
  if cmake --build "$build" --target help 2>/dev/null | grep -q dcd_vs_cgal; then
    cmake --build "$build" --target dcd_vs_cgal >&2
  fi
fi
exec /usr/bin/python3 "$here/bench_real.py" --skelcd "$build/tools/skelcd" \
  --dcd "$build/bench/real/dcd_vs_cgal" "$@"
