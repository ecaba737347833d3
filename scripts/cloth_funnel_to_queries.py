#!/usr/bin/env python3
"""Converts a CCD ground-truth set in the Sample-Scalable-CCD-Data layout (queries/<name>vf.csv,
<name>ee.csv with 8 rows `x_num,x_den,y_num,y_den,z_num,z_den` per query, and
mma_bool/<name>vf_mma_bool.json, <name>ee_mma_bool.json with the truth per query) into a
`skelcd ccd-queries` file (docs/ccd-queries.md): exact p/q coordinates, expected result last.

usage: cloth_funnel_to_queries.py DATASET_DIR NAME > queries.txt
example: scripts/cloth_funnel_to_queries.py assets/cloth-funnel 227 > /tmp/cloth.txt
"""
import csv
import json
import sys
from pathlib import Path


def convert(root: Path, name: str, kind: str, out) -> int:
    rows = list(csv.reader(open(root / "queries" / f"{name}{kind}.csv")))
    truth = json.load(open(root / "mma_bool" / f"{name}{kind}_mma_bool.json"))
    if len(rows) != 8 * len(truth):
        sys.exit(f"{name}{kind}.csv: {len(rows)} rows for {len(truth)} truth values (expected 8 per query)")
    for q, expected in enumerate(truth):
        coords = []
        for row in rows[8 * q: 8 * q + 8]:
            if len(row) != 6:
                sys.exit(f"{name}{kind}.csv: row {8 * q + 1}: expected 6 fields")
            coords += [f"{row[0]}/{row[1]}", f"{row[2]}/{row[3]}", f"{row[4]}/{row[5]}"]
        out.write(kind + " " + " ".join(coords) + f" {1 if expected else 0}\n")
    return len(truth)


def main() -> None:
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    root, name = Path(sys.argv[1]), sys.argv[2]
    sys.stdout.write(f"# {root} step {name}, converted by scripts/cloth_funnel_to_queries.py\n")
    n = convert(root, name, "vf", sys.stdout) + convert(root, name, "ee", sys.stdout)
    print(f"{n} queries", file=sys.stderr)


if __name__ == "__main__":
    main()
