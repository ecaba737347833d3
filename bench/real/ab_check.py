#!/usr/bin/env python3
"""A/B of two skelcd builds on one whole `skelcd check`: alternating runs (old first in odd
rounds, new first in even ones: on a VM whose speed drifts, a fixed order can favour one side),
each side's least wall time and least CPU time (user + system, the import's child included), its
largest peak RSS, and its least in-process times from the summary (`ms_per_interval`, the rows'
own; `setup_ms.total`, before the first row) — steadier than the whole process's — and whether
the two JSON summaries agree once the timings are left out (exit 1 when they do not).

    python3 bench/real/ab_check.py OLD_SKELCD NEW_SKELCD REPEAT [--rows] -- MODEL [check options…]

With --rows each check also writes its log (to a temporary folder: do not pass -o) and the least of
each row's own stage times over the rounds is printed per row (`skelcd inspect --frames`: total,
skin, refit, traverse, elementary ms) with old/new of the totals — on this project's VMs the steadier
reading (a clip's first interval, which pays its buffers' first touches, apart from the later
ones; one-step least-of-N wall times moved by ±5 % between runs of the same pair).

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


ROW_STAGES = ("total_ms", "skin_ms", "refit_ms", "traverse_ms", "elementary_ms")


def row_times(exe, log):
    """Each row's stage times (ROW_STAGES) of a check's log, in row order."""
    p = subprocess.run([exe, "inspect", "--frames", "--json", log], capture_output=True,
                       text=True)
    if p.returncode != 0:
        sys.exit(f"ab_check.py: {exe} inspect --frames {log} failed ({p.returncode}): "
                 f"{p.stderr.strip()}")
    return [tuple(row[k] for k in ROW_STAGES) for row in json.loads(p.stdout)["rows"]]


def print_rows(rows):
    """The least of each row's stage times per side, and old/new of the totals."""
    print("row: least over the rounds, ms (" + ", ".join(k[:-3] for k in ROW_STAGES) + ")")
    least = {side: [tuple(min(run[i][k] for run in runs) for k in range(len(ROW_STAGES)))
                    for i in range(len(runs[0]))] for side, runs in rows.items()}
    for i, (o, n) in enumerate(zip(least["old"], least["new"])):
        print(f"  {i:4d}  old " + " ".join(f"{v:8.2f}" for v in o) + "   new " +
              " ".join(f"{v:8.2f}" for v in n) + f"   old/new {o[0] / n[0]:.3f}")


def main():
    with_rows = len(sys.argv) > 4 and sys.argv[4] == "--rows"
    dash = 5 if with_rows else 4
    if len(sys.argv) < dash + 2 or sys.argv[dash] != "--":
        sys.exit(__doc__)
    sides = {"old": sys.argv[1], "new": sys.argv[2]}
    repeat = int(sys.argv[3])
    args = sys.argv[dash + 1:]
    if with_rows and any(a in ("-o", "--output") or a.startswith("--output=") for a in args):
        sys.exit("ab_check.py: --rows writes the logs itself: leave -o out")
    runs = {side: [] for side in sides}
    rows = {side: [] for side in sides}
    summaries = {}
    logs = tempfile.TemporaryDirectory()
    for round_index in range(repeat):
        order = ["old", "new"] if round_index % 2 == 0 else ["new", "old"]
        for side in order:
            # One path for both sides: the summaries name the log, and must not differ by it.
            log = os.path.join(logs.name, "check.h5")
            wall, cpu, rss, summary = run(sides[side], args + (["-o", log] if with_rows else []))
            runs[side].append(
                (wall, cpu, rss, summary["ms_per_interval"], summary["setup_ms"]["total"]))
            summaries[side] = without_timings(summary)
            if with_rows:
                rows[side].append(row_times(sides[side], log))
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
    if with_rows:
        if len(rows["old"][0]) != len(rows["new"][0]):
            sys.exit("ab_check.py: the two logs have different numbers of rows")
        print_rows(rows)
    logs.cleanup()
    same = summaries["old"] == summaries["new"]
    print("summaries (timings left out): " + ("identical" if same else "DIFFERENT"))
    sys.exit(0 if same else 1)


if __name__ == "__main__":
    main()
