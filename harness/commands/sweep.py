"""`torquebench sweep`: the identification error over robots x noise x seeds x methods x sample
counts, each cell one Ray task -> DIR/results.csv, DIR/summary.md, DIR/*.png."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from harness.commands import SUMMARY
from harness.sweep.grid import METHODS


def register(sub) -> None:
    p = sub.add_parser("sweep", help=SUMMARY["sweep"])
    p.add_argument("--robots", required=True, help="comma-separated robot names or URDF/MJCF paths")
    p.add_argument("--noise", required=True,
                   help="comma-separated torque noise levels (fractions of each joint's torque std)")
    p.add_argument("--seeds", required=True, type=int, help="number of seeds (0..N-1) per condition")
    p.add_argument("--methods", required=True, help=f"comma-separated, of: {', '.join(METHODS)}")
    p.add_argument("--samples", default="4000", help="comma-separated training sample counts "
                   "(default 4000)")
    p.add_argument("--address", default=None,
                   help="Ray cluster address to run the cells on (default: a local Ray instance)")
    p.add_argument("--out", required=True, help="output folder; a rerun reuses its finished cells")
    p.set_defaults(func=run)


def run(args) -> int:
    from harness.io import output_dir
    from harness.sweep.figures import write_figures
    from harness.sweep.grid import parse_grid
    from harness.sweep.run import run_sweep
    from harness.sweep.summary import bands, command, write_summary

    grid = parse_grid(args.robots, args.noise, args.seeds, args.methods, args.samples)
    out = Path(args.out)
    start = time.perf_counter()
    store, computed = run_sweep(grid, out, args.address)
    wall = time.perf_counter() - start
    results = [store.rows[c.key] for c in grid.cells()]
    output_dir(out)
    bs = bands(results)
    figures = write_figures(bs, results, grid, out)
    write_summary(out / "summary.md", grid, results, command(grid, out, args.address),
                  {"computed": computed, "wall": wall, "reused": len(grid) - computed}, list(figures))
    if store.dropped:
        print(f"torquebench sweep: warning: {store.dropped} torn last line of "
              f"{out / 'results.csv'} dropped, its cell runs again", file=sys.stderr)
    rate = f" ({computed / wall * 60:.1f} cells/min)" if computed else ""
    print(f"{computed} cells computed in {wall:.1f} s{rate}, {len(grid) - computed} reused; wrote "
          f"{out / 'results.csv'} ({len(store.rows)} rows), {out / 'summary.md'}, "
          + ", ".join(str(out / f) for f in figures))
    return 0
