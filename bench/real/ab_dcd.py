#!/usr/bin/env python3
"""Compare the full DCD of two builds of dcd_vs_cgal on the same frames, in one run.

    ab_dcd.py OLD_BINARY,NEW_BINARY ROUNDS MODEL [MODEL ...] [--samples S] [--repeat R]

For each model, the two binaries run alternately, ROUNDS times each, with --cpu-time (the calling
thread's CPU time, so that a second job on the machine does not count) and --json. Per frame it
keeps each binary's fastest run and prints, per model: the geometric mean over the frames of
OLD ms / NEW ms (above 1: NEW is faster) with its minimum and maximum, the exact triangle tests
summed over the frames for each binary, and each binary's geometric mean speed-up over CGAL.

Exits 1 when a binary fails, prints no frame, or reports a frame whose pairs are not CGAL's
(`identical` false): a faster DCD with other pairs is no result.
"""

import argparse
import json
import math
import subprocess
import sys


def geometric_mean(values):
    return math.exp(sum(math.log(v) for v in values) / len(values))


def run(binary, model, samples, repeat):
    """{sample: record} of one run, or raises RuntimeError naming the binary and model."""
    command = [binary, model, "--samples", str(samples), "--repeat", str(repeat),
               "--cpu-time", "--json"]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    if done.returncode not in (0, 1):  # dcd_vs_cgal exits 1 when pairs differ: checked below
        raise RuntimeError(f"{binary} {model}: exit {done.returncode}: {done.stderr.strip()}")
    frames = {}
    for line in done.stdout.splitlines():
        if not line.startswith("{"):
            continue
        record = json.loads(line)
        if not record["identical"]:
            raise RuntimeError(f"{binary} {model}: sample {record['sample']} has other pairs "
                               "than CGAL")
        frames[record["sample"]] = record
    if not frames:
        raise RuntimeError(f"{binary} {model}: no frame in its output: {done.stderr.strip()}")
    return frames


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("binaries", help="OLD,NEW: two dcd_vs_cgal binaries")
    parser.add_argument("rounds", type=int, help="runs of each binary per model, alternating")
    parser.add_argument("models", nargs="+", help="model files or frame folders")
    parser.add_argument("--samples", type=int, default=4, help="frames per model (default 4)")
    parser.add_argument("--repeat", type=int, default=5, help="repeats per run (default 5)")
    args = parser.parse_args()
    binaries = args.binaries.split(",")
    if len(binaries) != 2 or not all(binaries):
        parser.error("binaries must be OLD,NEW")
    if args.rounds < 1:
        parser.error("rounds must be at least 1")
    try:
        for model in args.models:
            best = [{}, {}]
            for _ in range(args.rounds):
                for side, binary in enumerate(binaries):
                    for sample, record in run(binary, model, args.samples, args.repeat).items():
                        kept = best[side].get(sample)
                        if kept is None or record["skelcd_ms"] < kept["skelcd_ms"]:
                            best[side][sample] = record
            old, new = best
            if sorted(old) != sorted(new):
                raise RuntimeError(f"{model}: the two binaries posed other samples")
            # A frame timed at 0 ms (below the clock: a model with no pair to test) has no ratio.
            ratios = [old[s]["skelcd_ms"] / new[s]["skelcd_ms"] for s in sorted(new)
                      if old[s]["skelcd_ms"] > 0 and new[s]["skelcd_ms"] > 0]
            tests = [sum(side[s].get("tt_tests", 0) for s in side) for side in best]
            vs_cgal = [[side[s]["cgal_ms"] / side[s]["skelcd_ms"] for s in side
                        if side[s]["cgal_ms"] > 0 and side[s]["skelcd_ms"] > 0] for side in best]
            if not ratios or not all(vs_cgal):
                print(f"{model}: frames below the clock's resolution, no ratio; "
                      f"triangle tests {tests[0]} -> {tests[1]}", flush=True)
                continue
            print(f"{model}: old/new ms {geometric_mean(ratios):.3f} "
                  f"(min {min(ratios):.3f}, max {max(ratios):.3f}); "
                  f"triangle tests {tests[0]} -> {tests[1]}; "
                  f"x CGAL old {geometric_mean(vs_cgal[0]):.2f}, "
                  f"new {geometric_mean(vs_cgal[1]):.2f}", flush=True)
    except (RuntimeError, OSError, json.JSONDecodeError, KeyError) as error:
        print(f"ab_dcd: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
