#!/usr/bin/python3
"""The collision events of every rigged, animated character (the bundled ones and Debian's, the
list of scripts/bench_default_method.py), each checked over its first clip against its rest pose
with the default options (issue 13: "gives an events table that fits on one screen").

Per model it runs `skelcd info MODEL --json` (triangles, rest_pose_deviation),
`skelcd check MODEL --threads 1 --json` and `skelcd check MODEL --threads 1` (the text summary,
whose events block it counts: from the `events` line to the line before `baseline`), and prints a
Markdown table: root events (the `events` list of --json: those not merged into another; how many
merged into them in brackets), new / baseline / allowed DCD pairs and CCD contacts, the lines of
the events block, the most bones of one event and info's rest_pose_deviation; the models without
any finding share one row. Then the events seen at one sample only and, per model, how many events
repeat the bones of another (a contact that comes back after more than 2 samples, or slides more
than a ring of triangles per sample, starts a new event; so does a second region).

  scripts/survey_events.py [build/tools/skelcd] [--cap 180] [--models FILE…] [--no-debian]
"""

import argparse
import importlib.util
import sys
from collections import Counter
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
spec = importlib.util.spec_from_file_location("bench_default_method",
                                              REPO / "scripts/bench_default_method.py")
bench = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bench)


def events_block(text):
    lines = text.splitlines()
    start = next((i for i, l in enumerate(lines) if l.startswith("events")), None)
    if start is None:
        return 0, len(lines)
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("baseline")),
               len(lines))
    return end - start, len(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("skelcd", nargs="?", default=str(REPO / "build/tools/skelcd"))
    ap.add_argument("--cap", type=float, default=180.0, help="seconds one run may take")
    ap.add_argument("--models", nargs="+", help="these models instead of the characters")
    ap.add_argument("--no-debian", action="store_true", help="bundled characters only")
    args = ap.parse_args()

    models = bench.character_models(args.skelcd, args.models, not args.no_debian)
    rows = []
    for model in models:
        name = bench.short_name(model)
        d = bench.info(args.skelcd, model) or {}
        s, _, frames = bench.run_capped(args.skelcd, model, None, args.cap)
        extra = ("--frames", frames) if frames else ()
        text, _ = bench.check(args.skelcd, model, None, extra=extra, json_out=False)
        block, total = events_block(text)
        ev = s["events"]
        bones = Counter(tuple(sorted(e["bones"])) for e in ev)
        rows.append({
            "model": name, "triangles": d.get("triangles"), "samples": s["frames"], "cut": frames,
            "events": len(ev),
            "merged": sum(len(e.get("merged_events") or []) for e in ev),
            "dcd": (s["new_dcd_pairs"], s["baseline_dcd_pairs"], s["allowed_dcd_pairs"]),
            "ccd": (s["new_ccd_contacts"], s["baseline_ccd_contacts"], s["allowed_ccd_contacts"]),
            "block": block, "lines": total,
            "max_bones": max((len(e["bones"]) for e in ev), default=0),
            "one_sample": sum(1 for e in ev if e["first_sample"] == e["last_sample"]),
            "repeats": sum(n - 1 for n in bones.values()),
            "rest_dev": d.get("rest_pose_deviation"),
            # the bounding box's diagonal, as info's own "% of the model's size"
            "size": sum((b - a) ** 2 for a, b in zip(d["bounding_box"]["min"],
                                                     d["bounding_box"]["max"])) ** 0.5
            if d.get("bounding_box") else None,
        })
        w = rows[-1]
        print(f"# {name}: {w['events']} events, block {w['block']} lines", file=sys.stderr)

    print("| model | triangles | samples | events (+ merged) | DCD pairs new / baseline / allowed "
          "| CCD contacts new / baseline / allowed | events block lines | most bones in one event "
          "| rest_pose_deviation (% of size) |")
    print("|---|---|---|---|---|---|---|---|---|")
    quiet = []
    for w in rows:
        if not any(w["dcd"]) and not any(w["ccd"]) and w["events"] == 0:
            quiet.append(w)
            continue
        samples = f"{w['samples']}" + (f" (cut: --frames {w['cut']})" if w["cut"] else "")
        dev = (f"{w['rest_dev']:.3g} ({100 * w['rest_dev'] / w['size']:.0f} %)"
               if w["rest_dev"] is not None and w["size"] else "-")
        merged = f" (+{w['merged']})" if w["merged"] else ""
        print(f"| {w['model']} | {w['triangles']} | {samples} | {w['events']}{merged} "
              f"| {' / '.join(map(str, w['dcd']))} | {' / '.join(map(str, w['ccd']))} "
              f"| {w['block']} | {w['max_bones']} | {dev} |")
    if quiet:
        print(f"| {len(quiet)} models without any finding (below) | {min(w['triangles'] for w in quiet)}"
              f"–{max(w['triangles'] for w in quiet)} | {min(w['samples'] for w in quiet)}"
              f"–{max(w['samples'] for w in quiet)} | 0 | 0 / 0 / 0 | 0 / 0 / 0 "
              f"| {max(w['block'] for w in quiet)} | 0 | |")
    print()
    if quiet:
        print("without any finding: " + ", ".join(w["model"] for w in quiet))
    print(f"largest events block: {max(w['block'] for w in rows)} lines; "
          f"most root events: {max(w['events'] for w in rows)}; "
          f"events seen at one sample only: {sum(w['one_sample'] for w in rows)}")
    print("events repeating the bones of an earlier one (a contact back after more than 2 samples, "
          "or a second region): " + ", ".join(f"{w['model']} {w['repeats']} of {w['events']}"
                                               for w in rows if w["repeats"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
