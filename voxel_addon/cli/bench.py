"""bench --out DIR: the fixed, seeded benchmark (CSV + PNG plots)."""
from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("bench", help="measure speed and memory; writes DIR/bench.csv and plots")
    p.add_argument("--out", required=True, type=Path, help="output folder")
    from ..bench.runner import AREAS
    p.add_argument("--area", action="append", choices=AREAS, help="only this area (repeatable)")
    p.add_argument("--quick", action="store_true", help="smaller sizes, for a smoke run")
    return p


def run(args):
    from ..bench.runner import run as run_bench
    path = run_bench(args.out, args.area, args.quick)
    print(path)
