"""bench --out DIR: the fixed, seeded benchmark (CSV + PNG plots); with --baseline REV,
ratios against another revision run alternately on the same machine."""
from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("bench", help="measure speed and memory; writes DIR/bench.csv and plots")
    p.add_argument("--out", required=True, type=Path, help="output folder")
    from ..bench.runner import AREAS
    p.add_argument("--area", action="append", choices=AREAS, help="only this area (repeatable)")
    p.add_argument("--quick", action="store_true", help="smaller sizes, for a smoke run "
                   "(with --baseline and no --area: the storage and world areas, 3 rounds in "
                   "about a minute)")
    p.add_argument("--baseline", metavar="REV", help="also run the areas at git revision REV "
                   "(a temporary worktree) alternating with this tree; the CSV gets ratios")
    p.add_argument("--rounds", type=int, default=3, metavar="N",
                   help="with --baseline: runs per side, alternating (default 3)")
    return p


def run(args):
    if args.baseline:
        from ..bench.compare import run as compare
        path = compare(args.out, args.baseline, args.area, args.quick, args.rounds)
    else:
        from ..bench.runner import run as run_bench
        path = run_bench(args.out, args.area, args.quick)
    print(path)
