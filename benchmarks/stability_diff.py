"""Where two methods of a stability map differ: every cell one holds and the other does not.

    PYTHONPATH=. python benchmarks/stability_diff.py [CSV] [--a "tissue, thesis"] [--b rigid_torsion]

Reads a CSV of benchmarks/stability_map.py (default benchmarks/out/stability_map_v3.csv), prints
each map as one compact text grid per method (one character per cell: H held, s slipped, d
dropped, X diverged, . refused; rows as in the map, columns left to right), then the cells where
``--a`` holds and ``--b`` does not, and the reverse, with the lift, largest tilt and (carry maps)
in-hand slide of both.
"""

from __future__ import annotations

import argparse
import csv
from collections import defaultdict
from pathlib import Path

OUT = Path(__file__).resolve().parent / "out"
CHAR = {2: "H", 1: "s", 0: "d", -1: "X", -2: "."}


def load(path: Path) -> dict:
    """{map: {method: {(row_value, col_value): row}}} and each map's axes, in the CSV's order."""
    cells: dict = defaultdict(lambda: defaultdict(dict))
    axes: dict = {}
    for r in csv.DictReader(open(path)):
        m = r.get("map", "")
        cells[m][r["method"]][(r["row_value"], r["col_value"])] = r
        rows, cols = axes.setdefault(m, (r["row_param"], [], r["col_param"], []))[1::2]
        if r["row_value"] not in rows:
            rows.append(r["row_value"])
        if r["col_value"] not in cols:
            cols.append(r["col_value"])
    return cells, axes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("csv", nargs="?", type=Path, default=OUT / "stability_map_v3.csv")
    parser.add_argument("--a", default="tissue, thesis")
    parser.add_argument("--b", default="rigid_torsion")
    args = parser.parse_args()
    cells, axes = load(args.csv)
    a_only, b_only, n_cells = [], [], 0
    for m, by_method in cells.items():
        rname, rows, cname, cols = axes[m]
        print(f"\n[{m}] rows {rname} {', '.join(rows)}; columns {cname} {', '.join(cols)}")
        for method, grid in by_method.items():
            lines = ["".join(CHAR[int(grid[(rv, cv)]["outcome"])] for cv in cols) for rv in rows]
            print(f"  {method:>20}: {' '.join(lines)}")
        if args.a not in by_method or args.b not in by_method:
            continue
        for rv in rows:
            for cv in cols:
                ra, rb = by_method[args.a][(rv, cv)], by_method[args.b][(rv, cv)]
                oa, ob = int(ra["outcome"]), int(rb["outcome"])
                if oa == -2 or ob == -2:
                    continue
                n_cells += 1
                if (oa == 2) != (ob == 2):
                    (a_only if oa == 2 else b_only).append((m, rname, rv, cname, cv, ra, rb))

    def show(title: str, found: list) -> None:
        print(f"\n{title}: {len(found)} of {n_cells} cells both methods ran")
        for m, rname, rv, cname, cv, ra, rb in found:
            detail = "; ".join(f"{name} {r['label']} lift {r['lift_mm']} mm, tilt {r['tilt_deg']} deg, slide "
                               f"{r['slide_mm']} mm" for name, r in ((args.a, ra), (args.b, rb)))  # fmt: skip
            print(f"  [{m}] {rname}={rv}, {cname}={cv}: {detail}")

    show(f"{args.a} holds, {args.b} does not", a_only)
    show(f"{args.b} holds, {args.a} does not", b_only)


if __name__ == "__main__":
    main()
