#!/usr/bin/env python3
"""A/B of two skelcd builds on any one command (`info MODEL`, `check …`): alternating runs (old
first in even rounds, new first in odd ones), each side's least and median wall time. For short
commands such as `info`, where the import is most of the time and one run's noise is several
milliseconds; bench/real/ab_check.py does more for `check`.

    python3 bench/real/ab_command.py OLD_SKELCD NEW_SKELCD ROUNDS -- COMMAND [ARGS…]

Example (docs/benchmarks.md, "The import child's heap on huge pages"):
    python3 bench/real/ab_command.py /tmp/skelcd-old build/tools/skelcd 15 -- \\
        info assets/characters/CesiumMan-dense.glb --json
"""
import statistics
import subprocess
import sys
import time


def main(argv):
    if len(argv) < 6 or argv[4] != "--":
        sys.exit(__doc__)
    old, new, rounds = argv[1], argv[2], int(argv[3])
    args = argv[5:]
    walls = {old: [], new: []}
    for i in range(rounds):
        for binary in (old, new) if i % 2 == 0 else (new, old):
            start = time.perf_counter()
            run = subprocess.run([binary] + args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
            walls[binary].append(time.perf_counter() - start)
            if run.returncode != 0:
                sys.exit(f"{binary} {' '.join(args)} failed (exit {run.returncode}):\n"
                         + run.stderr.decode(errors="replace"))
    for name, binary in (("old", old), ("new", new)):
        w = walls[binary]
        print(f"{name}: least {1e3 * min(w):.1f} ms  median {1e3 * statistics.median(w):.1f} ms")
    print(f"old/new: least {min(walls[old]) / min(walls[new]):.3f}  "
          f"median {statistics.median(walls[old]) / statistics.median(walls[new]):.3f}")


if __name__ == "__main__":
    main(sys.argv)
