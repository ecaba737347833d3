#!/usr/bin/env python3
"""A/B of two skelcd builds on one whole `skelcd check`: alternating runs (old first in odd
rounds, new first in even ones: on a VM whose speed drifts, a fixed order can favour one side),
each side's least wall time and least CPU time (user + system, the import's child included), its
largest peak RSS, and its least in-process times from the summary (`ms_per_interval`, the rows'
own; `setup_ms.total`, before the first row) — steadier than the whole process's — and whether
the two JSON summaries agree once the timings are left out (exit 1 when they do not).

    python3 bench/real/ab_check.py OLD_SKELCD NEW_SKELCD REPEAT -- MODEL [check options…]

Example (set-up alone: one sample, docs/benchmarks.md "parallel"):
    python3 bench/real/ab_check.py /tmp/skelcd-old build/tools/skelcd 9 -- \\
        /usr/share/assimp/models/X/BCN_Epileptic.X --method dynamic --threads 2 --frames 0:1
"""
import json
import os
import subprocess
import sys
import tempfile
import time


def without_timings(x):
    """The summary without its timing fields (total_ms, ms_per_interval, stages_ms, …)."""
    if isinstance(x, dict):
        return {k: without_timings(v) for k, v in x.items() if "ms" not in k.split("_")}
    if isinstance(x, list):
        return [without_timings(v) for v in x]
    return x


def run(exe, args):
    """(wall s, CPU s, peak RSS KiB, JSON summary) of one check (os.wait4: this child's usage)."""
    with tempfile.TemporaryFile(mode="w+") as err:
        start = time.perf_counter()
        p = subprocess.Popen(
            [exe, "check", *args, "--json"], stdout=subprocess.PIPE, stderr=err, text=True)
        with p.stdout:
            out = p.stdout.read()
        _, status, usage = os.wait4(p.pid, 0)
        wall = time.perf_counter() - start
        code = os.waitstatus_to_exitcode(status)
        p.returncode = code  # reaped by wait4: Popen must not wait for it again
        if code != 0:
            err.seek(0)
            sys.exit(f"ab_check.py: {exe} check {' '.join(args)} failed ({code}): "
                     f"{err.read().strip()}")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss, json.loads(out)


def main():
    if len(sys.argv) < 6 or sys.argv[4] != "--":
        sys.exit(__doc__)
    sides = {"old": sys.argv[1], "new": sys.argv[2]}
    repeat = int(sys.argv[3])
    args = sys.argv[5:]
    runs = {side: [] for side in sides}
    summaries = {}
    for round_index in range(repeat):
        order = ["old", "new"] if round_index % 2 == 0 else ["new", "old"]
        for side in order:
            wall, cpu, rss, summary = run(sides[side], args)
            runs[side].append(
                (wall, cpu, rss, summary["ms_per_interval"], summary["setup_ms"]["total"]))
            summaries[side] = without_timings(summary)
    best = {
        side: (min(r[0] for r in rs), min(r[1] for r in rs), max(r[2] for r in rs),
               min(r[3] for r in rs), min(r[4] for r in rs))
        for side, rs in runs.items()
    }
    for side, (wall, cpu, rss, per_row, setup) in best.items():
        print(f"{side}: wall {wall * 1e3:9.1f} ms  cpu {cpu * 1e3:9.1f} ms  peak RSS "
              f"{rss / 1024:7.1f} MiB  ms_per_interval {per_row:9.3f}  set-up {setup:8.1f} ms")
    o, n = best["old"], best["new"]
    print(f"old/new: wall {o[0] / n[0]:.3f}  cpu {o[1] / n[1]:.3f}  peak RSS {o[2] / n[2]:.3f}  "
          f"ms_per_interval {o[3] / n[3]:.3f}  set-up {o[4] / n[4]:.3f}")
    same = summaries["old"] == summaries["new"]
    print("summaries (timings left out): " + ("identical" if same else "DIFFERENT"))
    sys.exit(0 if same else 1)


if __name__ == "__main__":
    main()
