#!/usr/bin/env bash
# make demo: the main job on a bundled model.
set -euo pipefail
build=${1:-build}
exe="$build/tools/skelcd"
"$exe" --help
