#!/usr/bin/env bash
# Runs the libFuzzer harnesses (fuzz/, docs/fuzzing.md) one after another, each for FUZZ_SECONDS
# (default 600), at nice 19 so a build beside it keeps the CPU.
#   scripts/fuzz.sh [BUILD_DIR] [HARNESS...]     # BUILD_DIR default build-fuzz; HARNESS e.g. scene
# Each harness reads its committed seeds (fuzz/corpus/NAME/) and writes new corpus entries to
# BUILD_DIR/fuzz/corpus/NAME/ (scratch, kept between runs), crashing inputs to
# BUILD_DIR/fuzz/artifacts/NAME/ and its output to BUILD_DIR/fuzz/logs/NAME.log.
# assimp_import and log_reader run with -fork=1 -ignore_crashes=1 (assimp 5.2 crashes on many
# malformed files, libhdf5 leaks on damaged metadata): every crashing input is re-run and sorted by
# the top of its stack into the library's (listed, not a failure) and ours (a failure).
# Exit status: 0 when no harness crashed in our code, 1 otherwise. The table of the runs is in
# BUILD_DIR/fuzz/summary.md.
set -uo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-build-fuzz}
shift || true
[[ "$build" = /* ]] || build="$root/$build"
seconds=${FUZZ_SECONDS:-600}
all=(scene ccd_queries frame_mesh trajectory srdf log_reader assimp_import)
harnesses=("$@")
[[ ${#harnesses[@]} -eq 0 ]] && harnesses=("${all[@]}")

out="$build/fuzz"
mkdir -p "$out/logs"
summary="$out/summary.md"
{
  echo "| harness | seconds | executions | corpus (seeds + new) | crashes |"
  echo "|---|---|---|---|---|"
} >"$summary"

# -malloc_limit_mb/-rss_limit_mb below make a huge allocation a finding, not a machine hang (ASan's
# allocator_may_return_null stays off: a refused allocation would become a std::bad_alloc that the
# harness swallows). UBSan aborts (cmake/skelcd_fuzz.cmake); leaks inside libassimp/libfontconfig
# are suppressed as in make sanitize, and libhdf5's (fuzz/lsan.supp).
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
export LSAN_OPTIONS="suppressions=$root/fuzz/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
export SKELCD_ASSETS="$root/assets"

# The module of the first stack frame of a sanitizer report that is neither the sanitizer/libFuzzer
# runtime nor libc/libstdc++/libm: "assimp", "hdf5", "ours" (the harness binary: our code and
# what is inlined into it) or "unknown".
crash_owner() {
  awk '
    /^ *#[0-9]+ / {
      line = $0
      # An unsymbolized frame: a library by its name, else sanitizer runtime internals.
      if (line !~ / in /) {
        if (line ~ /libassimp/) { print "assimp"; exit }
        if (line ~ /libhdf5/) { print "hdf5"; exit }
        next
      }
      if (line ~ / in (main|fuzzer::)[ (]/) next
      if (line ~ / in (__interceptor_|__asan|__sanitizer|__ubsan|__lsan|fuzzer::|__libc_|_start|abort|raise|malloc|calloc|realloc|free|operator new|operator delete|__cxa_|__gxx_|_Unwind)/) next
      if (line ~ /libc\.so|libstdc\+\+\.so|libm\.so|libgcc_s\.so|ld-linux/) next
      # A frame of the harness binary without a source line is the runtime compiled into it: a
      # sanitizer interceptor (memmove, memcpy, strlen, fread, …) or libFuzzer. Ours has lines.
      if (line ~ /\/fuzz_[a-z_]+\+0x/ && line !~ /skelcd::|LLVMFuzzerTestOneInput/) next
      if (line ~ /libassimp/) { print "assimp"; exit }
      if (line ~ /libhdf5/) { print "hdf5"; exit }
      if (line ~ /\/fuzz_[a-z_]+\+0x|\/work\/|skelcd::/ || line ~ /\.(cpp|hpp|h):[0-9]+/) { print "ours"; exit }
    }
    END { }' "$1" | head -n 1
}

# Re-runs one artifact alone RUNS times (at most 90 s) into REPORT, the sanitizers' reports
# appended.
rerun() {
  local exe=$1 artifact=$2 report=$3 runs=$4
  ASAN_OPTIONS="handle_abort=1:log_path=$artifact.san${ASAN_OPTIONS:+:$ASAN_OPTIONS}" \
    UBSAN_OPTIONS="$UBSAN_OPTIONS:log_path=$artifact.san" \
    timeout 90 nice -n 19 "$exe" -handle_abrt=0 -rss_limit_mb=2048 -malloc_limit_mb=2048 \
    -timeout=60 -runs="$runs" "$artifact" >"$report" 2>&1
  cat "$artifact".san.* >>"$report" 2>/dev/null
  rm -f "$artifact".san.*
}

status=0
for name in "${harnesses[@]}"; do
  exe="$build/fuzz/fuzz_$name"
  seeds="$root/fuzz/corpus/$name"
  scratch="$out/corpus/$name"
  artifacts="$out/artifacts/$name"
  log="$out/logs/$name.log"
  if [[ ! -x "$exe" ]]; then
    echo "fuzz: $exe is missing (cmake --build $build --target fuzz_$name)" >&2
    status=1
    continue
  fi
  mkdir -p "$scratch" "$artifacts"
  args=(-max_total_time="$seconds" -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=30
        -print_final_stats=1 -artifact_prefix="$artifacts/")
  [[ -f "$root/fuzz/$name.dict" ]] && args+=(-dict="$root/fuzz/$name.dict")
  # The system library whose own crashes a harness lists without failing (run in fork mode).
  library=""
  [[ "$name" == assimp_import ]] && library=assimp
  [[ "$name" == log_reader ]] && library=hdf5
  if [[ -n "$library" ]]; then
    args+=(-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1)
  fi
  echo "fuzz: $name for ${seconds}s (log $log)" >&2
  # Only the artifacts of this run count (older ones stay in the folder for reference).
  stamp="$out/logs/$name.start"
  touch "$stamp"
  start=$(date +%s)
  # New entries go to the first corpus folder (scratch); the committed seeds are only read.
  nice -n 19 "$exe" "${args[@]}" "$scratch" "$seeds" >"$log" 2>&1
  rc=$?
  elapsed=$(( $(date +%s) - start ))

  # Executions: the final stats of a normal run, the last progress line of a fork run.
  execs=$(grep -o 'stat::number_of_executed_units: [0-9]*' "$log" | tail -n 1 | awk '{print $2}')
  [[ -z "$execs" ]] && execs=$(grep -oE '^#[0-9]+' "$log" | tail -n 1 | tr -d '#')
  corpus="$(find "$seeds" -type f | wc -l) + $(find "$scratch" -type f | wc -l)"

  # Sort every crashing input by the owner of its stack (re-run alone, at most 60 s). The
  # sanitizers also write to a log file and ASan, not libFuzzer, handles abort(): import_rig
  # points stderr at a temporary file while assimp reads, which would swallow the report.
  crashes=""
  ours=0
  while IFS= read -r a; do
    report="$a.report"
    if [[ ! -f "$report" ]]; then
      rerun "$exe" "$a" "$report" 1
      # A clean single run may still crash on a later one: a wild read inside an uninstrumented
      # library faults only when it lands on unmapped memory, which depends on the heap's layout.
      if [[ -z "$(crash_owner "$report")" ]] && grep -q '^Executed ' "$report"; then
        rerun "$exe" "$a" "$report" 100
      fi
    fi
    owner=$(crash_owner "$report")
    # No report at all but no clean finish either: it died while stderr was captured, i.e.
    # inside assimp's ReadFile/ApplyPostProcessing (skinning/assimp_import.cpp).
    if [[ -z "$owner" && "$name" == assimp_import ]] && ! grep -q '^Executed ' "$report"; then
      owner=assimp
    fi
    # A clean re-run: not reproducible alone (state built up over a fork job) or a suppressed leak.
    [[ -z "$owner" ]] && grep -q '^Executed ' "$report" && owner=not-reproduced
    owner=${owner:-unknown}
    crashes+="$(basename "$a") ($owner); "
    [[ -n "$library" && ("$owner" == "$library" || "$owner" == not-reproduced) ]] || ours=$((ours + 1))
  done < <(find "$artifacts" -maxdepth 1 -type f -newer "$stamp" \
             \( -name 'crash-*' -o -name 'oom-*' -o -name 'timeout-*' -o -name 'leak-*' \) \
             ! -name '*.report' | sort)
  if [[ -z "$library" && $rc -ne 0 && $ours -eq 0 ]]; then
    ours=1  # a failure that left no artifact (e.g. the harness did not start)
    crashes+="exit status $rc without an artifact; "
  fi
  [[ $ours -gt 0 ]] && status=1
  echo "| $name | $elapsed | ${execs:-?} | $corpus | ${crashes:-none} |" >>"$summary"
  echo "fuzz: $name: ${elapsed}s, ${execs:-?} executions, corpus $corpus, crashes: ${crashes:-none}" >&2
done

cat "$summary"
[[ $status -eq 0 ]] || echo "fuzz: a harness crashed in our code (see $out/artifacts, $out/logs)" >&2
exit $status
