#!/usr/bin/env bash
# make bench: every benchmark under bench/, with the build type in the context.
set -euo pipefail
build=${1:-build}
for b in $(find "$build/bench" -type f -executable -name 'bm_*' | sort); do
  echo "== $b"
  "$b"
done
