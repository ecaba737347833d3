#!/usr/bin/env python3
"""Runs `skelcd info` on every model file under a folder (default: Debian's assimp-testmodels,
/usr/share/assimp/models) and sorts each run into one of:

  loaded        exit 0
  refused       exit 1 with exactly one line on stderr that names the file
  crashed       killed by a signal, a sanitizer report, or an exit status other than 0/1
  over-budget   peak memory (the process and its children) above --budget-mib
  hung          still running after --timeout seconds (killed)
  noisy         refused with more than one line on stderr, or a line that does not name the file

It prints a table (Markdown with --markdown) and the files of every class but loaded/refused,
and exits 1 when any file crashed, went over budget or hung (so `make sweep` fails then).

  scripts/sweep_models.py build/tools/skelcd [FOLDER…] [--budget-mib 4096] [--timeout 120]
"""

import argparse
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

# Files that are not models: images, materials, text, archives of textures, scripts.
NOT_MODELS = {
    ".png", ".jpg", ".jpeg", ".tga", ".bmp", ".dds", ".gif", ".tif", ".tiff", ".psd", ".pcx", ".hdr",
    ".ktx", ".ktx2", ".webp", ".mtl", ".txt", ".md", ".html", ".htm", ".pdf", ".py", ".sh", ".cfg",
    ".ini", ".material", ".program", ".cg", ".glsl", ".hlsl", ".vert", ".frag", ".shader", ".skin",
    ".bin", ".log", ".json", ".xsd", ".dtd", ".license", ".rtf", ".doc", ".wav", ".mp3", ".ogg",
}
SKIP_DIRS = {"ReferenceImages", "SourceFiles", "ParsingFiles"}


def model_files(roots):
    for root in roots:
        root = Path(root)
        if root.is_file():
            yield root
            continue
        for path in sorted(root.rglob("*")):
            if not path.is_file() or any(part in SKIP_DIRS for part in path.parts):
                continue
            suffix = path.suffix.lower()
            if suffix in NOT_MODELS or path.name.lower() in {"readme", "license", "copying"}:
                continue
            if path.name.lower().startswith(("readme", "license", "copying", "credits")):
                continue
            yield path


def run_one(skelcd, path, timeout, budget_kib):
    """(class, peak KiB, seconds, first stderr line)."""
    start = time.monotonic()
    proc = subprocess.Popen(
        [skelcd, "info", str(path)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        start_new_session=True,
    )
    err = []
    reader = threading.Thread(target=lambda: err.append(proc.stderr.read()))
    reader.start()
    hung = False
    # wait4 gives this child's rusage; its peak RSS includes its reaped children (the import probe).
    while True:
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            break
        if time.monotonic() - start > timeout:
            hung = True
            os.killpg(proc.pid, signal.SIGKILL)
            pid, status, usage = os.wait4(proc.pid, 0)
            break
        time.sleep(0.005)
    reader.join()
    code = os.waitstatus_to_exitcode(status)
    proc.returncode = code  # reaped here; keeps Popen from waiting again
    peak_kib = usage.ru_maxrss
    seconds = time.monotonic() - start
    lines = [l for l in (err[0] if err else b"").decode("utf-8", "replace").splitlines() if l.strip()]
    first = lines[0] if lines else ""
    if hung:
        return "hung", peak_kib, seconds, first
    if peak_kib > budget_kib:
        return "over-budget", peak_kib, seconds, first
    if code == 0:
        return "loaded", peak_kib, seconds, first
    sanitizer = any("Sanitizer" in l or "runtime error:" in l for l in lines)
    if code < 0 or code not in (0, 1) or sanitizer:
        return "crashed", peak_kib, seconds, first
    if len(lines) == 1 and str(path) in lines[0]:
        return "refused", peak_kib, seconds, first
    return "noisy", peak_kib, seconds, first


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("skelcd")
    parser.add_argument("roots", nargs="*", default=["/usr/share/assimp/models"])
    parser.add_argument("--budget-mib", type=float, default=4096.0)
    parser.add_argument("--timeout", type=float, default=120.0)
    parser.add_argument("--markdown", action="store_true")
    parser.add_argument("--verbose", action="store_true", help="one line per file")
    args = parser.parse_args()

    classes = ["loaded", "refused", "noisy", "crashed", "over-budget", "hung"]
    found = {c: [] for c in classes}
    files = list(model_files(args.roots))
    peak_overall = (0, "")
    started = time.monotonic()
    for i, path in enumerate(files):
        kind, peak, seconds, first = run_one(args.skelcd, path, args.timeout, args.budget_mib * 1024)
        found[kind].append((path, first, peak, seconds))
        if peak > peak_overall[0]:
            peak_overall = (peak, str(path))
        if args.verbose:
            print(f"{kind:12s} {peak / 1024:8.1f} MiB {seconds:6.2f} s  {path}", flush=True)
        elif sys.stderr.isatty():
            print(f"\r{i + 1}/{len(files)} files", end="", file=sys.stderr, flush=True)
    if sys.stderr.isatty() and not args.verbose:
        print(file=sys.stderr)

    total = len(files)
    if args.markdown:
        print("| files | " + " | ".join(classes) + " |")
        print("|---|" + "---|" * len(classes))
        print(f"| {total} | " + " | ".join(str(len(found[c])) for c in classes) + " |")
    else:
        print(f"{total} files: " + ", ".join(f"{len(found[c])} {c}" for c in classes))
    print(f"largest peak memory: {peak_overall[0] / 1024:.0f} MiB ({peak_overall[1]}); "
          f"budget {args.budget_mib:.0f} MiB; {time.monotonic() - started:.0f} s in all")
    for c in ["noisy", "crashed", "over-budget", "hung"]:
        for path, first, peak, seconds in found[c]:
            print(f"{c}: {path}: {first}")
    bad = sum(len(found[c]) for c in ["crashed", "over-budget", "hung"])
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
