#!/usr/bin/env bash
# Speedup of `skelcd check --threads N` over `--threads 1` (docs/benchmarks.md, "parallel").
# Runs the two alternately REPEAT times per method and keeps each one's fastest wall time, so a
# load that comes and goes hits both alike; prints the load average before and after. Beside the
# wall times, the CPU seconds (user + system, the import's child included) of each, the least of
# the REPEAT runs. A parallel run that costs more CPU than the serial one does extra work, spins
# (oneTBB's idle workers wait busily for a while before they sleep) or shares its cores with
# another load; the wall-time speedup alone does not say which of these slowed it. Last, the least
# `setup_ms.total` of each (the check's --json: its wall time before the first row, the model's
# import not included; docs/check.md): the stretch no thread count shortens.
#   scripts/bench_parallel.sh [SKELCD] [MODEL]      (env: THREADS=2 REPEAT=3 METHODS="bvh dynamic"
#                                                    ARGS="extra check options")
set -euo pipefail
SKELCD=${1:-build/tools/skelcd}
MODEL=${2:-/usr/share/assimp/models/X/BCN_Epileptic.X}
THREADS=${THREADS:-2}
REPEAT=${REPEAT:-3}
METHODS=${METHODS:-"bvh dynamic"}
ARGS=${ARGS:-}

# measure METHOD THREADS: one check; sets WALL and CPU, in seconds (bash's `time`: real, and user +
# sys of the process and the children it waited for). A failing check stops the script with its
# messages.
ERRORS=$(mktemp)
SUMMARY=$(mktemp)
trap 'rm -f "$ERRORS" "$SUMMARY"' EXIT
measure() {
  local times status=0
  TIMEFORMAT='%R %U %S'
  # shellcheck disable=SC2086
  times=$({ time "$SKELCD" check "$MODEL" --method "$1" --threads "$2" --json $ARGS > "$SUMMARY" 2> "$ERRORS"; } 2>&1) ||
    status=$?
  if [ "$status" -ne 0 ]; then
    echo "bench_parallel.sh: $SKELCD check $MODEL --method $1 --threads $2 failed (exit $status):" >&2
    cat "$ERRORS" >&2
    exit 1
  fi
  read -r WALL user sys <<< "$times"
  CPU=$(awk -v u="$user" -v s="$sys" 'BEGIN { printf "%.3f", u + s }')
  SETUP=$(python3 -c 'import json, sys; print("%.1f" % json.load(open(sys.argv[1]))["setup_ms"]["total"])' "$SUMMARY")
}
min() { awk -v a="$1" -v b="$2" 'BEGIN { print (a == "" || b < a) ? b : a }'; }

echo "model   $MODEL $ARGS"
echo "cores   $(nproc); load before: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-10s %12s %12s %9s %12s %12s %9s %11s %11s\n' method "threads 1 s" "threads $THREADS s" speedup \
  "cpu 1 s" "cpu $THREADS s" "cpu ratio" "set-up 1 ms" "set-up $THREADS ms"
for method in $METHODS; do
  serial="" parallel="" serial_cpu="" parallel_cpu="" serial_setup="" parallel_setup=""
  for ((i = 0; i < REPEAT; i++)); do
    measure "$method" 1
    serial=$(min "$serial" "$WALL")
    serial_cpu=$(min "$serial_cpu" "$CPU")
    serial_setup=$(min "$serial_setup" "$SETUP")
    measure "$method" "$THREADS"
    parallel=$(min "$parallel" "$WALL")
    parallel_cpu=$(min "$parallel_cpu" "$CPU")
    parallel_setup=$(min "$parallel_setup" "$SETUP")
  done
  printf '%-10s %12s %12s %9s %12s %12s %9s %11s %11s\n' "$method" "$serial" "$parallel" \
    "$(awk -v s="$serial" -v p="$parallel" 'BEGIN { printf "%.2fx", s / p }')" \
    "$serial_cpu" "$parallel_cpu" \
    "$(awk -v s="$serial_cpu" -v p="$parallel_cpu" 'BEGIN { printf "%.2f", p / s }')" \
    "$serial_setup" "$parallel_setup"
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
