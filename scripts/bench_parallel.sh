#!/bin/sh
# Speedup of `skelcd check --threads N` over `--threads 1` (docs/benchmarks.md, "parallel").
# Runs the two alternately REPEAT times per method and keeps each one's fastest wall time, so a
# load that comes and goes hits both alike; prints the load average before and after.
#   scripts/bench_parallel.sh [SKELCD] [MODEL]      (env: THREADS=2 REPEAT=3 METHODS="bvh dynamic"
#                                                    ARGS="extra check options")
set -eu
SKELCD=${1:-build/tools/skelcd}
MODEL=${2:-/usr/share/assimp/models/X/BCN_Epileptic.X}
THREADS=${THREADS:-2}
REPEAT=${REPEAT:-3}
METHODS=${METHODS:-"bvh dynamic"}
ARGS=${ARGS:-}

now() { date +%s.%N; }
seconds() {  # seconds METHOD THREADS: wall time of one check
  start=$(now)
  # shellcheck disable=SC2086
  "$SKELCD" check "$MODEL" --method "$1" --threads "$2" $ARGS > /dev/null
  end=$(now)
  awk -v a="$start" -v b="$end" 'BEGIN { printf "%.3f", b - a }'
}
min() { awk -v a="$1" -v b="$2" 'BEGIN { print (a == "" || b < a) ? b : a }'; }

echo "model   $MODEL $ARGS"
echo "cores   $(nproc); load before: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-10s %12s %12s %9s\n' method "threads 1 s" "threads $THREADS s" speedup
for method in $METHODS; do
  serial=""
  parallel=""
  i=0
  while [ "$i" -lt "$REPEAT" ]; do
    serial=$(min "$serial" "$(seconds "$method" 1)")
    parallel=$(min "$parallel" "$(seconds "$method" "$THREADS")")
    i=$((i + 1))
  done
  printf '%-10s %12s %12s %9s\n' "$method" "$serial" "$parallel" \
    "$(awk -v s="$serial" -v p="$parallel" 'BEGIN { printf "%.2fx", s / p }')"
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
