#!/usr/bin/python3
"""`check --method auto` against `--method bvh` on every rigged, animated character: the bundled
ones (assets/characters) and those among Debian's assimp test models (/usr/share/assimp/models),
over each one's first clip, whole (issue 13: the default method becomes `auto` once it is never
much slower than `bvh`).

For each model it runs `skelcd check MODEL --threads 1 --json --method M` for M = bvh, auto,
alternately, --repeat times each, keeps the fastest `ms_per_interval` (the wall time of the
rows; also the median, to show the noise) and the least CPU time (user + system) of the whole
command, loading and auto's segmentation included, and checks that every run found
the same things as the first bvh run: dcd_pairs, ccd_vf, ccd_ee, the labelled counts and the
events. A difference is printed as MISMATCH and the script exits 1 (it would be a bug: both
methods are meant to report exactly the same findings).

A run that would take longer than --cap seconds is cut to the first samples that fit (--frames
0:K, estimated from a 20-interval probe) and marked in the table.

Which Debian models: every file `scripts/sweep_models.py` would try whose `skelcd info --json`
has at least one bone and whose first clip lasts more than 0 s (SMD files load with a clip of
0 s: one sample, no interval, nothing to time).

  scripts/bench_default_method.py [build/tools/skelcd] [--repeat 5] [--cap 180] [--json-dir DIR]
                                  [--models FILE…] [--no-debian]

Prints a Markdown table, then the geometric mean, worst and best ratio auto/bvh over every model
and over those whose bvh run takes at least --min-ms per interval; --json-dir keeps every run's
JSON (MODEL-METHOD-REP.json) for later reading (scripts/survey_events.py can reuse them).
"""

import argparse
import importlib.util
import json
import math
import os
import resource
import statistics
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
BUNDLED = [
    "assets/characters/CesiumMan.glb",
    "assets/characters/CesiumMan-dense.glb",
    "assets/characters/Fox.glb",
    "assets/characters/RiggedFigure.glb",
    "assets/characters/RobotExpressive.glb",
    "assets/characters/ninja/ninja.mesh",
    "assets/characters/stormtrooper/stormtrooper.dae",
]
DEBIAN = "/usr/share/assimp/models"
# What must be equal between two runs of one model (everything but times and culling work).
FINDINGS = [
    "frames", "intervals", "first_sample", "last_sample", "dcd_pairs", "ccd_vf", "ccd_ee",
    "new_dcd_pairs", "new_ccd_contacts", "baseline_dcd_pairs", "baseline_ccd_contacts",
    "allowed_dcd_pairs", "allowed_ccd_contacts", "frames_with_contacts",
    "frames_with_interpenetration", "intervals_with_contacts", "events",
]


def info(skelcd, model):
    r = subprocess.run([skelcd, "info", str(model), "--json"], capture_output=True, text=True,
                       stdin=subprocess.DEVNULL, timeout=300)
    if r.returncode != 0:
        return None
    try:
        return json.loads(r.stdout)
    except ValueError:
        return None


def debian_models(skelcd, folder=DEBIAN):
    """Rigged (bones >= 1), animated (first clip longer than 0 s) models under folder."""
    spec = importlib.util.spec_from_file_location("sweep_models", REPO / "scripts/sweep_models.py")
    sweep = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(sweep)
    found = []
    for path in sweep.model_files([folder]):
        d = info(skelcd, path)
        if d and d.get("bones", 0) >= 1 and d.get("clips") and d["clips"][0]["duration_s"] > 0:
            found.append(str(path))
    return found


def character_models(skelcd, extra=None, debian=True):
    models = list(extra) if extra else [str(REPO / m) for m in BUNDLED]
    if debian and not extra:
        models += debian_models(skelcd)
    return models


def short_name(model):
    p = Path(model)
    try:
        return str(p.resolve().relative_to(REPO))
    except ValueError:
        pass
    try:
        return str(p.relative_to(DEBIAN))
    except ValueError:
        return str(p)


def check(skelcd, model, method, frames=None, extra=(), timeout=None, json_out=True):
    """(summary dict or text, CPU seconds of the command and its children: user + system);
    raises subprocess.TimeoutExpired."""
    cmd = [skelcd, "check", str(model), "--threads", "1", *extra]
    if method:
        cmd += ["--method", method]
    if json_out:
        cmd.append("--json")
    if frames:
        cmd += ["--frames", frames]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    r = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL,
                       timeout=timeout)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: exit {r.returncode}: {r.stderr.strip()}")
    return (json.loads(r.stdout) if json_out else r.stdout), cpu


def findings(summary):
    return {k: summary.get(k) for k in FINDINGS}


def diff(a, b):
    return [k for k in FINDINGS if a.get(k) != b.get(k)]


def run_capped(skelcd, model, method, cap, extra=(), json_out=True):
    """(output, CPU seconds, frames): the whole clip when one run fits in cap seconds, else
    frames '0:K' with K estimated from a 20-interval probe to take about half the cap."""
    try:
        out, seconds = check(skelcd, model, method, extra=extra, timeout=cap, json_out=json_out)
        return out, seconds, None
    except subprocess.TimeoutExpired:
        pass
    probe, _ = check(skelcd, model, method, frames="0:20", extra=extra)
    k = max(2, int(0.5 * cap * 1000.0 / max(probe["ms_per_interval"], 1e-3)))
    frames = f"0:{k}"
    out, seconds = check(skelcd, model, method, frames=frames, extra=extra, json_out=json_out)
    return out, seconds, frames


def geomean(values):
    return math.exp(sum(map(math.log, values)) / len(values)) if values else math.nan


def summary_line(label, rows, key):
    if not rows:
        return f"{label}: no model"
    worst = max(rows, key=lambda w: w[key])
    best = min(rows, key=lambda w: w[key])
    return (f"{label} ({len(rows)} models): geometric mean {geomean([w[key] for w in rows]):.2f}, "
            f"worst {worst[key]:.2f} ({worst['model']}), best {best[key]:.2f} ({best['model']})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("skelcd", nargs="?", default=str(REPO / "build/tools/skelcd"))
    ap.add_argument("--repeat", type=int, default=5, help="runs per method (alternating)")
    ap.add_argument("--cap", type=float, default=180.0, help="seconds one run may take")
    ap.add_argument("--min-ms", type=float, default=0.01,
                    help="models whose bvh run takes less per interval are listed but left out "
                         "of the second summary line (their times are a few microseconds)")
    ap.add_argument("--json-dir", help="keep every run's JSON here")
    ap.add_argument("--models", nargs="+", help="these models instead of the characters")
    ap.add_argument("--no-debian", action="store_true", help="bundled characters only")
    args = ap.parse_args()

    models = character_models(args.skelcd, args.models, not args.no_debian)
    if args.json_dir:
        os.makedirs(args.json_dir, exist_ok=True)
    load = os.getloadavg()
    print(f"# {len(models)} models, {args.repeat} runs per method, fastest kept; "
          f"load average {load[0]:.2f} at the start", file=sys.stderr)

    rows, mismatches = [], []
    for model in models:
        name = short_name(model)
        # An untimed bvh run first: it decides whether to cut the clip and warms the caches.
        _, _, frames = run_capped(args.skelcd, model, "bvh", args.cap)
        ms = {"bvh": [], "auto": []}
        cpu = {"bvh": [], "auto": []}
        reference = None
        for rep in range(args.repeat):
            for method in ("bvh", "auto"):
                s, seconds = check(args.skelcd, model, method, frames)
                if args.json_dir:
                    stem = name.replace("/", "_").replace(" ", "_")
                    Path(args.json_dir, f"{stem}-{method}-{rep}.json").write_text(json.dumps(s))
                if reference is None:
                    reference = s
                else:
                    bad = diff(reference, s)
                    if bad:
                        msg = (f"MISMATCH {name} {method} run {rep}: " +
                               ", ".join(f"{k} {reference.get(k)!r:.60} vs {s.get(k)!r:.60}"
                                         for k in bad))
                        print(msg, file=sys.stderr)
                        mismatches.append(msg)
                ms[method].append(s["ms_per_interval"])
                cpu[method].append(seconds)
        r = reference
        d = info(args.skelcd, model)
        w = {
            "model": name, "triangles": d["triangles"] if d else None, "samples": r["frames"],
            "cut": frames, "bvh": min(ms["bvh"]), "auto": min(ms["auto"]),
            "median_ratio": statistics.median(ms["auto"]) / statistics.median(ms["bvh"]),
            "bvh_cpu": min(cpu["bvh"]), "auto_cpu": min(cpu["auto"]),
            "findings": f"{r['dcd_pairs']} / {r['ccd_vf']} / {r['ccd_ee']}",
            "equal": not any(m.startswith(f"MISMATCH {name} ") for m in mismatches),
        }
        w["ratio"] = w["auto"] / w["bvh"]
        w["cpu_ratio"] = w["auto_cpu"] / w["bvh_cpu"]
        rows.append(w)
        print(f"# {name}: bvh {w['bvh']:.4g} auto {w['auto']:.4g} ms/interval "
              f"({w['ratio']:.2f}x; medians {w['median_ratio']:.2f}x)", file=sys.stderr)

    print("| model | triangles | samples | bvh ms/interval | auto ms/interval | auto/bvh "
          "| (medians) | bvh CPU s (command) | auto CPU s (command) | auto/bvh (command) "
          "| DCD / VF / EE | equal |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for w in rows:
        samples = f"{w['samples']}" + (f" (cut: --frames {w['cut']})" if w["cut"] else "")
        print(f"| {w['model']} | {w['triangles']} | {samples} | {w['bvh']:.4g} | {w['auto']:.4g} "
              f"| {w['ratio']:.2f} | ({w['median_ratio']:.2f}) | {w['bvh_cpu']:.3f} "
              f"| {w['auto_cpu']:.3f} | {w['cpu_ratio']:.2f} | {w['findings']} "
              f"| {'yes' if w['equal'] else '**NO**'} |")
    timed = [w for w in rows if w["bvh"] >= args.min_ms]
    print()
    print(summary_line("ms per interval, auto/bvh, every model", rows, "ratio"))
    print(summary_line(f"ms per interval, auto/bvh, models with bvh >= {args.min_ms} ms/interval",
                       timed, "ratio"))
    print(summary_line("the same, medians of the runs", timed, "median_ratio"))
    print(summary_line("whole command's CPU time, auto/bvh, every model", rows, "cpu_ratio"))
    print(f"findings equal in every run: {'yes' if not mismatches else 'NO'}")
    end = os.getloadavg()
    print(f"load average {load[0]:.2f} at the start, {end[0]:.2f} at the end", file=sys.stderr)
    for m in mismatches:
        print(m)
    return 1 if mismatches else 0


if __name__ == "__main__":
    sys.exit(main())
