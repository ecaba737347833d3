#!/usr/bin/env bash
# make demo: the main job on bundled models, under the build folder: what CesiumMan holds
# (`skelcd info`), one posed frame for a viewer (`skelcd export`), a clip check with its log
# (`skelcd check`), and a scene — CesiumMan with an attached cape — with its plan and summary.
set -euo pipefail
build=${1:-build}
exe="$build/tools/skelcd"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
model="$root/assets/characters/CesiumMan.glb"
out_dir="$build/demo"
mkdir -p "$out_dir"

echo "== skelcd info $model"
"$exe" info "$model"
echo
echo "== skelcd export $model --frame 12 -o $out_dir/CesiumMan_frame12.glb"
"$exe" export "$model" --frame 12 -o "$out_dir/CesiumMan_frame12.glb"
echo
echo "== skelcd check $model -o $out_dir/CesiumMan_check.h5"
"$exe" check "$model" -o "$out_dir/CesiumMan_check.h5"
echo
scene="$root/assets/scenes/cape.toml"
echo "== skelcd check $scene -o $out_dir/cape.h5   (a scene: its plan, then a summary per check)"
"$exe" check "$scene" -o "$out_dir/cape.h5"
echo
echo "demo: the posed mesh (frame 12 of the walk) is in $(cd "$out_dir" && pwd)/CesiumMan_frame12.glb"
