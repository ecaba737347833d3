#!/usr/bin/python3
"""`bvh`, `dynamic` and `auto` on the same models, the way a user runs them (docs/benchmarks.md
"`auto` on dense characters"): for each model, each method runs ROUNDS times, alternating, as

  skelcd check MODEL --method M --query ccd --threads 1 --json   (ms per CCD interval)
  skelcd check MODEL --method M --json                             (a default check: both queries,
                                                                    the default threads; wall time)

and the least of each is kept (the peak RSS, GNU time's, the largest). Prints per model the ratios
bvh/M per interval and in wall time, the wall times and peak RSS; exits 1 when a method's findings
(CCD contacts, DCD pairs) differ from `bvh`'s.

  python3 bench/real/methods_wall.py [--skelcd build/tools/skelcd] [--rounds 3] MODEL...

Denser copies of the bundled characters: bench/real/densify.py (Blender).
"""
import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent.parent
METHODS = ("bvh", "dynamic", "auto")
MODES = {"ccd": ["--query", "ccd", "--threads", "1"], "default": []}


def run(skelcd, model, method, extra):
    cmd = ["/usr/bin/time", "-f", "RSS=%M", skelcd, "check", model, "--method", method, "--json",
           *extra]
    start = time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.monotonic() - start
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd[3:])}: exit {p.returncode}: {p.stderr.strip()[:300]}")
    s = json.loads(p.stdout)
    rss = [float(l[4:]) for l in p.stderr.splitlines() if l.startswith("RSS=")][-1] / 1024.0
    return {"ms": s["ms_per_interval"], "wall": wall, "rss": rss,
            "findings": (s["ccd_vf"], s["ccd_ee"], s["dcd_pairs"])}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--skelcd", default=str(REPO / "build/tools/skelcd"))
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("models", nargs="+")
    args = ap.parse_args()
    differ = False
    for model in args.models:
        best = {}
        for _ in range(max(1, args.rounds)):
            for method in METHODS:
                for mode, extra in MODES.items():
                    r = run(args.skelcd, model, method, extra)
                    key = (method, mode)
                    if key not in best:
                        best[key] = r
                        continue
                    b = best[key]
                    if r["findings"] != b["findings"]:
                        raise RuntimeError(f"{model} {method} {mode}: findings differ between runs")
                    b["ms"] = min(b["ms"], r["ms"])
                    b["wall"] = min(b["wall"], r["wall"])
                    b["rss"] = max(b["rss"], r["rss"])
        line = [os.path.basename(model) + ":"]
        for method in METHODS[1:]:
            for mode in MODES:
                if best[(method, mode)]["findings"] != best[("bvh", mode)]["findings"]:
                    differ = True
                    line.append(f"DIFFERENT findings ({method}, {mode})")
            c, d = best[(method, "ccd")], best[(method, "default")]
            line.append(f"bvh/{method} {best[('bvh', 'ccd')]['ms'] / c['ms']:.2f} per interval, "
                        f"{best[('bvh', 'default')]['wall'] / d['wall']:.2f} wall "
                        f"({d['wall']:.2f} s, {d['rss']:.0f} MiB);")
        b = best[("bvh", "default")]
        line.append(f"bvh {b['wall']:.2f} s, {b['rss']:.0f} MiB")
        print(" ".join(line), flush=True)
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
