#!/usr/bin/env python3
"""Writes N random CCD queries in the `skelcd ccd-queries` format (docs/ccd-queries.md): each
query vf or ee with probability 1/2, its 8 points uniform in [-1,1]^3, written with 17 significant
digits (so the doubles are exactly the ones generated). No expected results.

usage: random_ccd_queries.py N [SEED] > queries.txt
"""
import random
import sys


def main() -> None:
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    n = int(sys.argv[1])
    random.seed(int(sys.argv[2]) if len(sys.argv) == 3 else 1)
    out = sys.stdout
    out.write(f"# {n} random queries, 8 points uniform in [-1,1]^3 each\n")
    for _ in range(n):
        kind = "vf" if random.random() < 0.5 else "ee"
        out.write(kind + " " + " ".join(repr(random.uniform(-1, 1)) for _ in range(24)) + "\n")


if __name__ == "__main__":
    main()
