#!/usr/bin/python3
"""Real assets in one run (issue 14, docs/benchmarks.md "Real assets"): for every bundled and
Debian rigged character and every cloth step, the DCD of posed frames against CGAL's
`self_intersections` and the CCD of the clip by `bvh`, `kdop`, `dynamic` and `auto`, with peak
memory, and the findings compared between them.

  scripts/bench_real.py [--skelcd build/tools/skelcd] [--dcd build/bench/real/dcd_vs_cgal]
                        [--samples 4] [--repeat 3] [--min-ms 50] [--cap 60] [--no-debian]
                        [--models FILE…]
                        [--cloth DIR…] [--json-out FILE]

DCD: `dcd_vs_cgal MODEL --json` (bench/real/dcd_vs_cgal.cpp; built by `make bench-real` when
libcgal-dev is installed) poses --samples frames spread over the first clip (each frame of a cloth
step) and times skelcd's `bvh` DCD and CGAL 5.5's self_intersections, one thread each, fastest of at
least --repeat runs and of as many as make --min-ms ms per frame and side, and compares the pairs
(CGAL's extra pairs at vertices its soup-to-mesh conversion duplicated are counted apart, see the
source). It also times `incremental`: the DCD a clip check runs at a sample after the first, the
previous sample's pairs updated from the interval's CCD contacts (culling/incremental_dcd.hpp; the
previous DCD and the CCD untimed, as the check has them).

CCD: `skelcd check MODEL --query ccd --threads 1 --method M --json -o LOG` for each method, each in
its own process so that its peak RSS (ru_maxrss from wait4) is its own, --ccd-repeat times (3):
the times are the fastest run's (a one-interval cloth step moved by 10-15 % between single runs;
DCD keeps the fastest of --repeat too), the peak RSS the largest run's. A clip whose bvh run takes
longer than --cap seconds is cut to the samples that fit (--frames 0:K, from a probe), the same for
every method. The contact sets are compared through the logs (every /contacts row's sample, kind
and features); `dynamic` needs a skeleton and is "n/a" on frame sequences.

Prints a Markdown table and summary lines: DCD speed-up over CGAL (geometric mean and minimum over
the frames of models with at least --min-triangles triangles), CCD ms per interval ratios bvh/M,
the ceiling of bvh/dynamic (bvh's ms over the `elementary` + `skin` ms that dynamic's run still
spends per interval: its ratio if its culling took no time at all), peak RSS above the process's
floor (`skelcd --help`) per triangle. Exits 1 when any pair or contact set differs, 2 on a failed
run.

Memory on the inputs of at least 10,000 triangles (the issue's "1 KiB per triangle plus what the
findings themselves need"), per method: the raw figure, (peak RSS - floor) / triangles, and beside
it the same minus the findings, (peak RSS - floor - findings) / triangles, where

  findings = n x (32 + 56) bytes + min(log, min(n, 8192) x 56 bytes)

- n: the most contacts of one interval (counted per /contacts `frame` in the method's log).
- In memory: while an interval is reported, the run holds each of its contacts twice: the
  method's culling::CcdContact (32 bytes, the query's FrameResult) and the interval's
  tools::ContactRow (56, the FrameReport, which the event tracker labels in place and, with
  `--query ccd`, hands back at once: tools/engine/runner.cpp, check_engine.cpp, events.hpp).
  Until 2026-12-06 the contacts' radix sort kept a buffer of their size per thread (32 more,
  culling/pair_sort.cpp; they are sorted in place now) and the tracker labelled a copy of the
  row and held it until the next interval (56 more, and 56 again while the next was copied). Counted at their sizes: what the vectors hold
  beyond (they grow by doubling) stays in the figure.
- The log writer converts the contacts into detail::ContactDisk rows (56 bytes) 8,192 at a time
  (since 2026-12-06; before, all of an interval's at once) before HDF5 writes them. That is counted only as far as the log raised the peak: `log` is measured, the
  peak RSS of the same command minus that of the command without `-o LOG`. The rest of `log` (about
  4 MiB whatever the findings, see cloth-funnel's 134 contacts: mostly libhdf5's own pages, about
  2.8 MiB resident once a file is written, and the metadata cache's 0.5 MB index; docs/benchmarks.md
  "Fixed costs") is not the findings' and stays in the figure.
tests/tools/test_log.cpp checks the sizes. On the cloth steps the heap peak is reached while
the in-memory copies are held (valgrind massif, docs/benchmarks.md "Real assets"); where a
peak is reached before any contact exists, "minus findings" understates it by up to n x 88 bytes.
"""

import argparse
import glob
import importlib.util
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
CCD_METHODS = ["bvh", "kdop", "dynamic", "auto"]
LARGE_TRIANGLES = 10000  # per-method memory line: inputs this large or larger
# Bytes of one CCD contact in each record held in memory while an interval is reported, and in the
# log writer's row buffer (the module docstring; tests/tools/test_log.cpp checks the sizes).
CONTACT_RECORD_BYTES = {"culling::CcdContact": 32, "tools::ContactRow (report)": 56}
CONTACT_DISK_BYTES = 56  # tools::detail::ContactDisk
DISK_ROWS_PER_APPEND = 8192  # the log writer's block (tools/io/log/log_writer.cpp, kRowsPerAppend)


def load_sibling(name):
    spec = importlib.util.spec_from_file_location(name, REPO / "scripts" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def run_measured(cmd, timeout):
    """(returncode, stdout, stderr, seconds, peak RSS in MiB) of one process. The peak comes from
    GNU time (/usr/bin/time -f %M): a child forked from this Python process would count the pages
    it inherited (the contact sets read so far) in its own ru_maxrss."""
    start = time.monotonic()
    marker = "__bench_real_maxrss_kib="
    cmd = ["/usr/bin/time", "-f", marker + "%M", *cmd]
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        p = subprocess.Popen(cmd, stdout=out, stderr=err, stdin=subprocess.DEVNULL)
        deadline = start + timeout if timeout else None
        while True:
            pid, status, usage = os.wait4(p.pid, os.WNOHANG)
            if pid:
                break
            if deadline and time.monotonic() > deadline:
                p.kill()
                os.wait4(p.pid, 0)
                raise subprocess.TimeoutExpired(cmd, timeout)
            time.sleep(0.02)
        seconds = time.monotonic() - start
        out.seek(0)
        err.seek(0)
        code = os.waitstatus_to_exitcode(status)
        lines = err.read().decode(errors="replace").splitlines()
        rss = [float(l[len(marker):]) for l in lines if l.startswith(marker)]
        lines = [l for l in lines if not l.startswith(marker)
                 and not l.startswith("Command exited with non-zero status")]
        return (code, out.read().decode(errors="replace"), "\n".join(lines), seconds,
                (rss[-1] if rss else usage.ru_maxrss) / 1024.0)


def contact_set(log):
    import h5py
    with h5py.File(log, "r") as f:
        c = f["contacts"][()]
    return set(zip(c["frame"].tolist(), c["kind"].tolist(), c["a_part"].tolist(),
                   c["a_index"].tolist(), c["a_side"].tolist(), c["b_part"].tolist(),
                   c["b_index"].tolist(), c["b_side"].tolist()))


def max_interval_contacts(contacts):
    """The most contacts of one interval in a contact_set."""
    per_frame = {}
    for row in contacts:
        per_frame[row[0]] = per_frame.get(row[0], 0) + 1
    return max(per_frame.values(), default=0)


def findings_mib(run):
    """What the findings take at the peak, MiB (the module docstring): the contacts' records in
    memory, computed, and the log writer's rows, as far as the measured log share goes."""
    n = run["max_interval_contacts"]
    rows = min(n, DISK_ROWS_PER_APPEND) * CONTACT_DISK_BYTES / 2.0**20
    return n * sum(CONTACT_RECORD_BYTES.values()) / 2.0**20 + min(max(run["log_mib"], 0.0), rows)


def dcd_rows(dcd, model, samples, repeat, min_ms, timeout):
    cmd = [dcd, model, "--json", "--samples", str(samples), "--repeat", str(repeat),
           "--min-ms", str(min_ms), "--methods", "bvh,incremental"]
    code, out, err, _, _ = run_measured(cmd, timeout)
    rows = [json.loads(line) for line in out.splitlines() if line.startswith("{")]
    if code == 2 or not rows:
        raise RuntimeError(f"{' '.join(cmd)}: exit {code}: {err.strip()[:300]}")
    return rows


CCD_REPEAT = 3  # runs of each CCD command (--ccd-repeat): the fastest one's times are kept


def ccd_run(skelcd, model, method, frames, log, timeout, with_log=True, repeat=None):
    """One method's CCD of the clip, run `repeat` times (CCD_REPEAT unless given) as the same
    command: the times (ms per interval and the stages) are the fastest run's, the peak RSS the
    largest, the contacts and the log the last run's (every run writes the same ones)."""
    cmd = [skelcd, "check", model, "--query", "ccd", "--threads", "1", "--method", method,
           "--json"]
    if with_log:
        cmd += ["-o", log]
    if frames:
        cmd += ["--frames", frames]
    best = None
    for _ in range(repeat or CCD_REPEAT):
        code, out, err, seconds, rss = run_measured(cmd, timeout)
        if code != 0:
            raise RuntimeError(f"{' '.join(cmd)}: exit {code}: {err.strip()[:300]}")
        s = json.loads(out)
        stages = s.get("stages_ms", {})
        run = {"ms_per_interval": s["ms_per_interval"], "intervals": s["intervals"],
               "contacts": s["ccd_vf"] + s["ccd_ee"], "rss_mib": rss, "seconds": seconds,
               "elementary_ms": stages.get("elementary", 0.0), "skin_ms": stages.get("skin", 0.0),
               "runs_ms_per_interval": [s["ms_per_interval"]]}
        if best is None:
            best = run
            continue
        if run["contacts"] != best["contacts"] or run["intervals"] != best["intervals"]:
            raise RuntimeError(f"{' '.join(cmd)}: {run['contacts']} contacts in one run, "
                               f"{best['contacts']} in another")
        run["runs_ms_per_interval"] = best["runs_ms_per_interval"] + [s["ms_per_interval"]]
        run["rss_mib"] = max(rss, best["rss_mib"])
        run["seconds"] = best["seconds"]
        if run["ms_per_interval"] >= best["ms_per_interval"]:
            for k in ("ms_per_interval", "elementary_ms", "skin_ms"):
                run[k] = best[k]
        best = run
    return best


def account_findings(skelcd, model, method, frames, run, contacts):
    """Adds to a large input's run what its findings take (findings_mib): the contacts of its
    largest interval and its peak without the log (one more run)."""
    run["max_interval_contacts"] = max_interval_contacts(contacts)
    bare = ccd_run(skelcd, model, method, frames, None, None, with_log=False)
    run["rss_mib_without_log"] = bare["rss_mib"]
    run["log_mib"] = run["rss_mib"] - bare["rss_mib"]
    run["findings_mib"] = findings_mib(run)


def geomean(values):
    return math.exp(sum(map(math.log, values)) / len(values)) if values else math.nan


def main():
    global CCD_REPEAT
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--skelcd", default=str(REPO / "build/tools/skelcd"))
    ap.add_argument("--dcd", default=str(REPO / "build/bench/real/dcd_vs_cgal"))
    ap.add_argument("--samples", type=int, default=4, help="posed frames per model for DCD")
    ap.add_argument("--repeat", type=int, default=3, help="DCD runs per frame (fastest kept)")
    ap.add_argument("--min-ms", type=float, default=50.0,
                    help="and more DCD runs until they add up to this many ms per frame and side "
                         "(a sub-ms frame's fastest of 3 moved by up to 45%%)")
    ap.add_argument("--cap", type=float, default=60.0, help="seconds one CCD run may take")
    ap.add_argument("--ccd-repeat", type=int, default=CCD_REPEAT,
                    help="runs of each CCD command; the fastest one's times are kept (a one-interval "
                         "cloth step's single run moved by 10-15%% from run to run)")
    ap.add_argument("--min-triangles", type=int, default=1000,
                    help="models below this are listed but left out of the summary lines")
    ap.add_argument("--models", nargs="+", help="these models instead of the characters")
    ap.add_argument("--no-debian", action="store_true", help="bundled characters only")
    ap.add_argument("--cloth", nargs="*",
                    default=sorted(glob.glob(str(REPO.parent / "shared/assets/cloth/*/frames"))),
                    help="frame-sequence folders (default: ../shared/assets/cloth/*/frames)")
    ap.add_argument("--json-out", help="write every figure here")
    args = ap.parse_args()
    CCD_REPEAT = max(1, args.ccd_repeat)

    bdm = load_sibling("bench_default_method")
    models = bdm.character_models(args.skelcd, args.models, not args.no_debian)
    models += list(args.cloth or [])
    have_cgal = os.access(args.dcd, os.X_OK)
    if not have_cgal:
        print(f"# {args.dcd} is missing (libcgal-dev not installed?): no DCD column",
              file=sys.stderr)
    load = os.getloadavg()
    print(f"# {len(models)} models; load average {load[0]:.2f} at the start", file=sys.stderr)

    # The process's own floor (libraries, no model): peak RSS is also given above it.
    floor_mib = run_measured([args.skelcd, "--help"], 60)[4]
    results, differ, failed = [], [], []
    tmp = tempfile.mkdtemp(prefix="bench_real_")
    for model in models:
        name = bdm.short_name(model)
        if "shared/assets/cloth" in model:
            name = Path(model).parent.name
        r = {"model": name, "path": model}
        print(f"# {name}", file=sys.stderr)
        try:
            if have_cgal:
                rows = dcd_rows(args.dcd, model, args.samples, args.repeat, args.min_ms,
                                20 * args.cap)
                r["triangles"] = rows[0]["triangles"]
                r["dcd"] = rows
                for row in rows:
                    if not row["identical"]:
                        differ.append(f"{name} DCD sample {row['sample']}: skelcd-only "
                                      f"{row['skelcd_only']}, CGAL-only {row['cgal_only']}")
            # The cut, decided by bvh and shared by every method.
            frames = None
            log = os.path.join(tmp, "bvh.h5")
            try:
                first = ccd_run(args.skelcd, model, "bvh", None, log, args.cap)
            except subprocess.TimeoutExpired:
                probe = ccd_run(args.skelcd, model, "bvh", "0:5", log, None, repeat=1)
                k = max(2, int(0.5 * args.cap * 1000.0 / max(probe["ms_per_interval"], 1e-3)))
                frames = f"0:{k}"
                first = ccd_run(args.skelcd, model, "bvh", frames, log, None)
            r["frames"] = frames
            r["ccd"] = {"bvh": first}
            reference = contact_set(log)
            large = r.get("triangles", 0) >= LARGE_TRIANGLES
            if large:
                account_findings(args.skelcd, model, "bvh", frames, first, reference)
            for method in CCD_METHODS[1:]:
                mlog = os.path.join(tmp, f"{method}.h5")
                try:
                    r["ccd"][method] = ccd_run(args.skelcd, model, method, frames, mlog, None)
                except RuntimeError as e:
                    if method == "dynamic" and ("skeleton" in str(e) or "bone" in str(e)):
                        r["ccd"][method] = None
                        continue
                    raise
                found = contact_set(mlog)
                if found != reference:
                    differ.append(f"{name} CCD {method}: contacts differ from bvh's")
                if large:
                    account_findings(args.skelcd, model, method, frames, r["ccd"][method], found)
        except (RuntimeError, subprocess.TimeoutExpired) as e:
            failed.append(f"{name}: {e}")
            print(f"# FAILED {name}: {e}", file=sys.stderr)
            continue
        results.append(r)

    # The table.
    print("| model | triangles | DCD frames | skelcd DCD ms | CGAL ms | × CGAL (min) | "
          "incremental ms | × CGAL (min) | pairs | "
          "CCD intervals | bvh ms | kdop ms | dynamic ms | auto ms | bvh/dynamic | bvh/auto | "
          "peak RSS MiB (bvh, kdop, dynamic, auto) | contacts |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    all_frames, all_incremental, per_model_tri = [], [], []
    for r in results:
        inc = [d for d in r.get("dcd", []) if d["method"] == "incremental"]
        dcd = [d for d in r.get("dcd", []) if d["method"] != "incremental"]
        tri = r.get("triangles", 0)
        ccd = r["ccd"]
        if dcd:
            # dcd_vs_cgal gives a null speed-up where a time is below its clock's resolution.
            speed = [d["speedup"] for d in dcd if d["speedup"] is not None]
            inc_speed = [d["speedup"] for d in inc if d["speedup"] is not None]
            inc_cols = (f"{sum(d['skelcd_ms'] for d in inc) / len(inc):.4f} | "
                        f"{geomean(inc_speed):.0f} ({min(inc_speed):.0f})") if inc_speed else "– | –"
            speed_cols = f"{geomean(speed):.2f} ({min(speed):.2f})" if speed else "–"
            dcd_cols = (f"{len(dcd)} | {sum(d['skelcd_ms'] for d in dcd) / len(dcd):.2f} | "
                        f"{sum(d['cgal_ms'] for d in dcd) / len(dcd):.2f} | "
                        f"{speed_cols} | {inc_cols} | "
                        f"{max(d['skelcd_pairs'] for d in dcd)}")
            if tri >= args.min_triangles:
                all_frames += speed
                all_incremental += inc_speed
        else:
            dcd_cols = "– | – | – | – | – | – | –"

        def ms(m):
            return f"{ccd[m]['ms_per_interval']:.2f}" if ccd.get(m) else "n/a"

        def ratio(m):
            if not ccd.get(m) or ccd[m]["ms_per_interval"] <= 0:
                return "n/a"
            return f"{ccd['bvh']['ms_per_interval'] / ccd[m]['ms_per_interval']:.2f}"

        rss = max(v["rss_mib"] for v in ccd.values() if v)
        rss_cols = ", ".join(f"{ccd[m]['rss_mib']:.0f}" if ccd.get(m) else "n/a"
                             for m in CCD_METHODS)
        cut = f" (0:{r['frames'].split(':')[1]})" if r.get("frames") else ""
        print(f"| {r['model']} | {tri} | {dcd_cols} | {ccd['bvh']['intervals']}{cut} | "
              f"{ms('bvh')} | {ms('kdop')} | {ms('dynamic')} | {ms('auto')} | {ratio('dynamic')} | "
              f"{ratio('auto')} | {rss_cols} | {ccd['bvh']['contacts']} |")
        if tri >= args.min_triangles:
            per_model_tri.append((r["model"], max(rss - floor_mib, 0.0) * 1024.0 / tri))

    print()
    if all_frames:
        print(f"DCD speed-up over CGAL (frames of models with >= {args.min_triangles} triangles, "
              f"{len(all_frames)} frames): geometric mean {geomean(all_frames):.2f}, "
              f"minimum {min(all_frames):.2f}")
    if all_incremental:
        print(f"Incremental DCD (a clip check's DCD after its first sample, from the previous "
              f"sample and the interval's CCD contacts) over CGAL ({len(all_incremental)} frames): "
              f"geometric mean {geomean(all_incremental):.0f}, minimum {min(all_incremental):.1f}")
    big = [r for r in results if r.get("triangles", 0) >= args.min_triangles]
    for m in CCD_METHODS[1:]:
        vals = [r["ccd"]["bvh"]["ms_per_interval"] / r["ccd"][m]["ms_per_interval"]
                for r in big if r["ccd"].get(m) and r["ccd"][m]["ms_per_interval"] > 0]
        if vals:
            print(f"CCD bvh/{m} per interval ({len(vals)} models): geometric mean "
                  f"{geomean(vals):.2f}, min {min(vals):.2f}, max {max(vals):.2f}")
    # What bvh/dynamic could reach if dynamic's culling cost nothing: it would still pose the
    # mesh and run the elementary tests its culling leaves (stages_ms, per interval).
    ceilings = []
    for r in big:
        d = r["ccd"].get("dynamic")
        floor = d["elementary_ms"] + d["skin_ms"] if d else 0.0
        if floor > 0:
            ceilings.append((r["model"], r["ccd"]["bvh"]["ms_per_interval"] / floor))
    if ceilings:
        print(f"CCD bvh/dynamic ceiling, bvh ms over dynamic's elementary + skin ms per interval "
              f"(culling for free; {len(ceilings)} models): "
              + ", ".join(f"{Path(m).name} {c:.1f}" for m, c in ceilings)
              + f"; below 10 on {sum(c < 10 for _, c in ceilings)}")
    if per_model_tri:
        worst = max(per_model_tri, key=lambda w: w[1])
        print(f"peak RSS above the process floor ({floor_mib:.0f} MiB, `skelcd --help`) per "
              f"triangle, any CCD method: worst {worst[1]:.2f} KiB ({worst[0]})")
    # Per method on the large inputs, where the per-triangle structures (not the importer's fixed
    # cost) decide the peak: the "1 KiB per triangle plus findings". The raw figure, and
    # beside it the same minus what the findings take (findings_mib, the module docstring).
    large = [r for r in results if r.get("triangles", 0) >= LARGE_TRIANGLES]
    for m in CCD_METHODS:
        vals = []
        for r in large:
            run = r["ccd"].get(m)
            if not run:
                continue
            raw = max(run["rss_mib"] - floor_mib, 0.0) * 1024.0 / r["triangles"]
            net = max(run["rss_mib"] - floor_mib - run["findings_mib"], 0.0) * 1024.0 / r["triangles"]
            vals.append((raw, net, r["model"]))
            print(f"peak RSS, {m}, {r['model']} ({r['triangles']} triangles): "
                  f"{run['rss_mib']:.1f} MiB ({run['rss_mib_without_log']:.1f} without the log); "
                  f"KiB per triangle above the floor {raw:.2f}, minus findings {net:.2f} "
                  f"(findings {run['findings_mib']:.1f} MiB: {run['max_interval_contacts']} "
                  f"contacts x {sum(CONTACT_RECORD_BYTES.values())} bytes in memory, log rows "
                  f"{min(max(run['log_mib'], 0.0), min(run['max_interval_contacts'], DISK_ROWS_PER_APPEND) * CONTACT_DISK_BYTES / 2.0**20):.1f} "
                  f"of the log's {run['log_mib']:.1f})")
        if vals:
            worst = max(vals)
            worst_net = max(vals, key=lambda v: v[1])
            print(f"peak RSS above the floor per triangle, {m}, models with >= {LARGE_TRIANGLES} "
                  f"triangles ({len(vals)}): worst {worst[0]:.2f} KiB ({worst[2]}); minus findings "
                  f"worst {worst_net[1]:.2f} KiB ({worst_net[2]})")
    for d in differ:
        print(f"DIFFERENT: {d}")
    for f in failed:
        print(f"FAILED: {f}")
    if args.json_out:
        Path(args.json_out).write_text(json.dumps(results, indent=1))
    if failed:
        return 2
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
