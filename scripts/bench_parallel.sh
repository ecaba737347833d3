#!/usr/bin/env bash
# Speedup of `skelcd check --threads N` over `--threads 1` (docs/benchmarks.md, "parallel").
# Runs the two alternately REPEAT times per method and keeps each one's fastest wall time, so a
# load that comes and goes hits both alike; prints the load average before and after. Beside the
# wall times, the CPU seconds (user + system, the import's child included) of each, the least of
# the REPEAT runs. A parallel run that costs more CPU than the serial one does extra work, spins
# (oneTBB's idle workers wait busily for a while before they sleep) or shares its cores with
# another load; the wall-time speedup alone does not say which of these slowed it.
#   scripts/bench_parallel.sh [SKELCD] [MODEL]      (env: THREADS=2 REPEAT=3 METHODS="bvh dynamic"
#                                                    ARGS="extra check options")
set -euo pipefail
SKELCD=${1:-build/tools/skelcd}
MODEL=${2:-/usr/share/assimp/models/X/BCN_Epileptic.X}
THREADS=${THREADS:-2}
REPEAT=${REPEAT:-3}
METHODS=${METHODS:-"bvh dynamic"}
ARGS=${ARGS:-}

# measure METHOD THREADS: "wall cpu" in seconds of one check (bash's `time`: real, user + sys of
# the process and the children it waited for).
measure() {
  local times
  TIMEFORMAT='%R %U %S'
  # shellcheck disable=SC2086
  times=$({ time "$SKELCD" check "$MODEL" --method "$1" --threads "$2" $ARGS > /dev/null; } 2>&1)
  awk '{ printf "%.3f %.3f", $1, $2 + $3 }' <<< "$times"
}
min() { awk -v a="$1" -v b="$2" 'BEGIN { print (a == "" || b < a) ? b : a }'; }

echo "model   $MODEL $ARGS"
echo "cores   $(nproc); load before: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-10s %12s %12s %9s %12s %12s %9s\n' method "threads 1 s" "threads $THREADS s" speedup \
  "cpu 1 s" "cpu $THREADS s" "cpu ratio"
for method in $METHODS; do
  serial="" parallel="" serial_cpu="" parallel_cpu=""
  for ((i = 0; i < REPEAT; i++)); do
    read -r wall cpu <<< "$(measure "$method" 1)"
    serial=$(min "$serial" "$wall")
    serial_cpu=$(min "$serial_cpu" "$cpu")
    read -r wall cpu <<< "$(measure "$method" "$THREADS")"
    parallel=$(min "$parallel" "$wall")
    parallel_cpu=$(min "$parallel_cpu" "$cpu")
  done
  printf '%-10s %12s %12s %9s %12s %12s %9s\n' "$method" "$serial" "$parallel" \
    "$(awk -v s="$serial" -v p="$parallel" 'BEGIN { printf "%.2fx", s / p }')" \
    "$serial_cpu" "$parallel_cpu" \
    "$(awk -v s="$serial_cpu" -v p="$parallel_cpu" 'BEGIN { printf "%.2f", p / s }')"
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
