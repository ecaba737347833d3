#!/usr/bin/env bash
# Crash safety of the log, measured: runs `skelcd check` on a rig at a high sample rate (a row
# every few milliseconds, so kills often land inside a write or a flush), kills it with SIGKILL
# at a random time, and reads the log back with `skelcd inspect --frames --json` (our reader) and
# `h5dump -d /frames` (HDF5's own). Counts the logs either one cannot read, and the logs whose rows
# are not the consecutive dcd/ccd rows 0, 1, 2, … they must be.
#   scripts/stress_kill.sh [SKELCD] [RUNS]      (default build/tools/skelcd, 100)
set -euo pipefail
SKELCD=${1:-build/tools/skelcd}
RUNS=${2:-100}
MODEL=${MODEL:-$(dirname "$0")/../assets/characters/Fox.glb}   # 576 triangles: a row every ~1 ms
DIR=$(mktemp -d /tmp/skelcd-stress-kill.XXXXXX)
trap 'rm -rf "$DIR"' EXIT
bad_reader=0; bad_h5dump=0; bad_rows=0; no_log=0; total_rows=0
for ((i = 1; i <= RUNS; i++)); do
  log="$DIR/run.h5"
  rm -f "$log"
  "$SKELCD" check "$MODEL" --fps 300 --threads 1 -o "$log" >/dev/null 2>&1 &
  pid=$!
  sleep "$(awk -v s="$RANDOM" 'BEGIN { printf "%.3f", 0.2 + (s % 800) / 1000 }')"
  kill -KILL "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  if [[ ! -e "$log" ]]; then no_log=$((no_log + 1)); continue; fi
  if ! h5dump -d /frames "$log" >/dev/null 2>&1; then bad_h5dump=$((bad_h5dump + 1)); fi
  if ! "$SKELCD" inspect "$log" --frames --json >"$DIR/rows.json" 2>"$DIR/err.txt"; then
    bad_reader=$((bad_reader + 1)); echo "run $i: $(cat "$DIR/err.txt")"; continue
  fi
  rows=$(python3 - "$DIR/rows.json" <<'PY'
import json, sys
frames = json.load(open(sys.argv[1]))["rows"]
for i, f in enumerate(frames):
    if f["sample"] != i // 2 or f["kind"] != ("dcd" if i % 2 == 0 else "ccd"):
        print(-1); sys.exit()
print(len(frames))
PY
)
  if [[ "$rows" == -1 ]]; then bad_rows=$((bad_rows + 1)); else total_rows=$((total_rows + rows)); fi
done
echo "runs $RUNS: killed before the log existed $no_log, unreadable by skelcd $bad_reader," \
     "by h5dump $bad_h5dump, rows out of order $bad_rows; $total_rows rows read in all"
[[ $bad_reader -eq 0 && $bad_h5dump -eq 0 && $bad_rows -eq 0 ]]
