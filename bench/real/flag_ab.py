#!/usr/bin/env python3
"""A/B of one skelcd build with and without a `check` flag: REPEAT rounds of both runs, the run
with the flag first in odd rounds and last in even ones (with it always first, Testwuson's
`dynamic` read 0.84x with --no-rigid-rows where alternating rounds read 1.08x: the first of two
back-to-back runs was the faster on this VM), each row's least total and traverse ms over the rounds
(`skelcd inspect --frames`: each row's own stage times, the steadier reading on these VMs), their
means over the rows with flag/without, the summaries' candidate pairs and set-up ms, and whether
the contacts agree (exit 1 when the VF or EE contact counts differ, or the logs' /contacts do).

    python3 bench/real/flag_ab.py SKELCD REPEAT FLAG -- MODEL [check options…]

Example (docs/benchmarks.md, "Rigid rows in `kdop`"):
    python3 bench/real/flag_ab.py build/tools/skelcd 5 --no-rigid-rows -- \\
        assets/characters/ninja/ninja.mesh --method kdop --query ccd --threads 1 --baseline none
"""
import json
import os
import subprocess
import sys
import tempfile


def run(exe, args, log):
    p = subprocess.run([exe, "check"] + args + ["-o", log, "--json"], capture_output=True,
                       text=True)
    if p.returncode != 0:
        sys.exit(f"flag_ab.py: {exe} check {' '.join(args)} failed ({p.returncode}): "
                 f"{p.stderr.strip()}")
    rows = subprocess.run([exe, "inspect", "--frames", "--json", log], capture_output=True,
                          text=True, check=True)
    contacts = subprocess.run(["h5dump", "-d", "/contacts", log], capture_output=True, text=True)
    body = [line for line in contacts.stdout.splitlines() if "HDF5" not in line]
    return (json.loads(p.stdout), [(r["total_ms"], r["traverse_ms"]) for r in
                                   json.loads(rows.stdout)["rows"]], body)


def main():
    if len(sys.argv) < 6 or sys.argv[4] != "--":
        sys.exit(__doc__)
    exe, repeat, flag, args = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[5:]
    if repeat < 1:
        sys.exit("flag_ab.py: REPEAT must be 1 or more")
    least, summary, contacts = {}, {}, {}
    with tempfile.TemporaryDirectory() as logs:
        log = os.path.join(logs, "check.h5")
        for r in range(repeat):
            for side in ("with", "without") if r % 2 == 0 else ("without", "with"):
                s, rows, body = run(exe, args + ([flag] if side == "with" else []), log)
                old = least.get(side)
                least[side] = rows if old is None else [
                    (min(a[0], b[0]), min(a[1], b[1])) for a, b in zip(old, rows)]
                summary[side], contacts[side] = s, body
    mean = {k: (sum(r[0] for r in v) / len(v), sum(r[1] for r in v) / len(v))
            for k, v in least.items() if v}
    w, wo = summary["with"], summary["without"]
    same = (w["ccd_vf"], w["ccd_ee"]) == (wo["ccd_vf"], wo["ccd_ee"]) and \
        contacts["with"] == contacts["without"]
    print(f"{os.path.basename(args[0])} {' '.join(args[1:])}: {len(least['with'])} rows; "
          f"ms per row with {flag} {mean['with'][0]:.3f}, without {mean['without'][0]:.3f}, "
          f"with/without {mean['with'][0] / mean['without'][0]:.3f}; traverse "
          f"{mean['with'][1]:.3f} / {mean['without'][1]:.3f}; candidate_pairs "
          f"{w['candidate_pairs']} / {wo['candidate_pairs']}; set-up ms "
          f"{w['setup_ms']['total']:.1f} / {wo['setup_ms']['total']:.1f}; contacts VF "
          f"{wo['ccd_vf']} EE {wo['ccd_ee']}, {'the same' if same else 'DIFFERENT'}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
