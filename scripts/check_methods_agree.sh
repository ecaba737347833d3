#!/usr/bin/env bash
# The issue's acceptance check on a whole clip (too slow for ctest's default label): every method
# must report the same DCD pairs and CCD VF/EE contacts as the brute-force reference — the same
# totals and, read back from the logs, the same sets of features per frame.
#   scripts/check_methods_agree.sh [BUILD_DIR] [MODEL] [extra check options…]
set -euo pipefail
build=${1:-build}
model=${2:-/usr/share/assimp/models/X/BCN_Epileptic.X}
shift $(( $# > 2 ? 2 : $# ))
exe="$build/tools/skelcd"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

for method in brute bvh kdop; do
  start=$(date +%s.%N)
  "$exe" check "$model" --method "$method" --json -o "$out/$method.h5" "$@" > "$out/$method.json"
  end=$(date +%s.%N)
  /usr/bin/python3 - "$out/$method.json" "$method" "$start" "$end" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
print(f"{sys.argv[2]:6s} dcd_pairs={j['dcd_pairs']} ccd_vf={j['ccd_vf']} ccd_ee={j['ccd_ee']} "
      f"frames={j['frames']} intervals={j['intervals']} ms/interval={j['ms_per_interval']:.3f} "
      f"wall={float(sys.argv[4]) - float(sys.argv[3]):.1f}s")
PY
done

/usr/bin/python3 - "$out" <<'PY'
import sys, h5py
def findings(path):
    with h5py.File(path, "r") as f:
        c = f["contacts"][:]
        p = f["dcd_pairs"][:]
    contacts = sorted(tuple(int(r[k]) for k in ("frame", "kind", "a_part", "a_index", "a_side",
                                                  "b_part", "b_index", "b_side")) for r in c)
    pairs = sorted(tuple(int(r[k]) for k in ("frame", "a_part", "a_index", "b_part", "b_index"))
                   for r in p)
    return contacts, pairs
reference = findings(f"{sys.argv[1]}/brute.h5")
ok = True
for method in ("bvh", "kdop"):
    got = findings(f"{sys.argv[1]}/{method}.h5")
    same = got == reference
    ok &= same
    print(f"{method} vs brute: {'identical' if same else 'DIFFERENT'} "
          f"({len(got[0])} contacts, {len(got[1])} DCD pairs)")
sys.exit(0 if ok else 1)
PY
