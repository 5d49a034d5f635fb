"""`torquebench study NAME --out DIR`: one long study, run on demand, with its report.

Studies (harness.studies) are the measurements too long for the bench: the 20-scenario
real-time study, the paper's identification and planning studies, ... Each writes the same
report as the bench (DIR/report.md, report.json, headline.md, figures/); exit 1 if it
raised, 3 if one of its checks failed, else 0. `torquebench study --list` names them.
"""

from __future__ import annotations

from pathlib import Path

from harness.commands import SUMMARY, add_chain_option, chain_option
from harness.commands.bench import Progress, command_line, machine, run_pipeline, verdict
from harness.errors import UserError
from harness.report.results import Context
from harness.report.writer import write_report
from harness.robots.registry import DEFAULT_ROBOT
from harness.robots.resolve import resolve_arm
from harness.studies import STUDIES, load_study


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "study", help=SUMMARY["study"],
        description="Studies: " + "; ".join(f"{k}: {v}" for k, v in STUDIES.items()) + ".")
    p.add_argument("name", nargs="?", help="the study (see --list)")
    p.add_argument("--out", help="output directory")
    p.add_argument("--list", action="store_true", help="name every study and exit")
    p.add_argument("--quick", action="store_true", help="the study's smoke-test size")
    p.add_argument("--robot", default=None, help=f"robot (default {DEFAULT_ROBOT})")
    add_chain_option(p)
    p.add_argument("--no-video", action="store_true", help="do not render videos")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.list:
        for name, text in STUDIES.items():
            print(f"{name}: {text}")
        return 0
    if args.name not in STUDIES:
        raise UserError(f"unknown study '{args.name}' (known: {', '.join(STUDIES)})")
    if not args.out:
        raise UserError("--out DIR is required")
    out_dir = Path(args.out)
    arm = resolve_arm(args.robot, chain=chain_option(args))
    arm.chain  # noqa: B018 - a robot that is no serial arm: one line, before any section
    out_dir.mkdir(parents=True, exist_ok=True)
    progress = Progress()
    ctx = Context(arm, out_dir, args.quick, not args.no_video, {})
    outcomes = run_pipeline(ctx, (args.name,), progress, load_study)
    args.sections, args.full = None, False
    meta = {"robot": args.robot or arm.reference, "quick": bool(args.quick), "study": args.name,
            "command": command_line(args).replace("torquebench bench",
                                                  f"torquebench study {args.name}"),
            "machine": machine(), "timing": {"elapsed_s": progress.elapsed}}
    write_report(out_dir, outcomes, meta)
    return verdict(outcomes, progress, out_dir, f"study {args.name}")
