"""`torquebench bench --out DIR`: every stage on one robot, one report.

Sections run in data-flow order (identification -> planning -> replay -> closeloop -> real
data), each given what the earlier ones handed on (harness.report.results.Context), the same
sections for every robot. A section that raises is reported as failed with its message.
The report is always written (harness.report.writer); the command then exits 1 if a section
failed, 3 if a check failed (each named on stderr), else 0. Targets never change the exit
status. `--full` also runs every study (harness.studies). Progress goes to stderr as one
line per event with the elapsed wall time.
"""

from __future__ import annotations

import os
import platform
import sys
import threading
import time
import traceback
import warnings
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path

from harness import interrupt
from harness.bench import SECTIONS, load_section
from harness.commands import SUMMARY, add_chain_option, chain_option
from harness.errors import UserError
from harness.report.results import Context
from harness.report.writer import SectionOutcome, write_report
from harness.robots.registry import DEFAULT_ROBOT
from harness.robots.resolve import resolve_arm
from harness.studies import STUDIES, load_study

HEARTBEAT = 30.0  # s between "still running" lines of a long section


class Progress:
    """Timestamped progress lines on stderr: '[  12.3 s] message'."""

    def __init__(self) -> None:
        self.start = time.perf_counter()

    @property
    def elapsed(self) -> float:
        return time.perf_counter() - self.start

    def __call__(self, message: str) -> None:
        print(f"[{self.elapsed:6.1f} s] {message}", file=sys.stderr, flush=True)

    @contextmanager
    def heartbeat(self, name: str):
        """Print '<name>: still running' every HEARTBEAT seconds until the block ends."""
        done = threading.Event()

        def beat() -> None:
            while not done.wait(HEARTBEAT):
                self(f"{name}: still running")

        thread = threading.Thread(target=beat, daemon=True)
        thread.start()
        try:
            yield
        finally:
            done.set()


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "bench", help=SUMMARY["bench"],
        description="Identification against the oracle, planning with the closed-form and the "
        "identified model, MuJoCo replay, closing the loop, real logs; writes DIR/report.md, "
        "DIR/report.json, DIR/headline.md and DIR/figures/*.png. Exit 0 when every check "
        "holds, 3 when a check fails, 1 when a section raises; targets never change it.",
    )
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--quick", action="store_true", help="fewer draws and timings")
    p.add_argument("--robot", default=None,
                   help=f"registered robot or URDF/MJCF path (default {DEFAULT_ROBOT}); every "
                   "robot gets the same sections, plus the extras its registry entry declares")
    add_chain_option(p)
    p.add_argument("--no-video", action="store_true", help="do not render replay videos")
    p.add_argument("--sections", default=None,
                   help=f"comma-separated sections to run, in pipeline order (default: all: "
                   f"{', '.join(SECTIONS)}); replay replays the plans of planning")
    p.add_argument("--full", action="store_true",
                   help=f"also run every study after the sections ({', '.join(STUDIES)})")
    p.set_defaults(func=run)


def chosen_sections(names: str | None) -> tuple[str, ...]:
    """The sections named (comma-separated), in pipeline order; all by default."""
    if names is None:
        return SECTIONS
    wanted = [n.strip() for n in names.split(",") if n.strip()]
    unknown = [n for n in wanted if n not in SECTIONS]
    if unknown or not wanted:
        raise UserError(f"--sections: unknown section(s) {', '.join(unknown) or '(none given)'} "
                        f"(known: {', '.join(SECTIONS)})")
    return tuple(n for n in SECTIONS if n in wanted)


def _error_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".rstrip(": ")


def run_one(name: str, module_of, ctx: Context, progress: Progress):
    """Run one section or study; never raises: the outcome records what happened."""
    progress(f"{name}: started")
    start = time.perf_counter()
    try:
        with progress.heartbeat(name), warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("default")
            result = module_of(name).run(ctx)
    except Exception as exc:
        seconds = time.perf_counter() - start
        traceback.print_exc(file=sys.stderr)
        progress(f"{name}: FAILED after {seconds:.1f} s: {_error_line(exc)}")
        return SectionOutcome(name, "failed", seconds, error=_error_line(exc)), None
    seconds = time.perf_counter() - start
    failed = [c.name for c in result.checks if not c.passed]
    progress(f"{name}: done in {seconds:.1f} s, {len(result.checks) - len(failed)} of "
             f"{len(result.checks)} checks hold")
    said = list(dict.fromkeys(f"{w.category.__name__}: {w.message}" for w in caught))
    for line in said:
        progress(f"{name}: warning: {line}")
    return SectionOutcome.of(name, result, seconds, said), result


def run_pipeline(ctx: Context, names, progress: Progress, module_of=load_section):
    """The named sections (or studies) in order, each given the earlier ones' results."""
    outcomes = []
    for name in names:
        outcome, result = run_one(name, module_of, ctx, progress)
        if result is not None:
            ctx.earlier[name] = result
        interrupt.check()  # Ctrl-C during a section that swallowed it: stop here
        outcomes.append(outcome)
    return outcomes


def run(args) -> int:
    out_dir = Path(args.out)
    arm = resolve_arm(args.robot, chain=chain_option(args))
    arm.chain  # noqa: B018 - a robot that is no serial arm: one line, before any section
    if out_dir.exists() and not out_dir.is_dir():
        raise UserError(f"--out {out_dir} exists and is not a directory")
    sections = chosen_sections(args.sections)
    started = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    out_dir.mkdir(parents=True, exist_ok=True)
    progress = Progress()
    progress(f"bench on '{arm.label}' -> {out_dir}{' (quick)' if args.quick else ''}")
    ctx = Context(arm, out_dir, args.quick, not args.no_video, {})
    outcomes = run_pipeline(ctx, sections, progress)
    if args.full:
        outcomes += run_pipeline(ctx, tuple(STUDIES), progress, load_study)
    meta = {"robot": args.robot or arm.reference, "quick": bool(args.quick), "sections": list(sections),
            "command": command_line(args), "machine": machine(),
            "timing": {"elapsed_s": progress.elapsed, "started_utc": started,
                       "load_average_at_start": os.getloadavg()[0]
                       if hasattr(os, "getloadavg") else None}}
    write_report(out_dir, outcomes, meta)
    return verdict(outcomes, progress, out_dir)


def verdict(outcomes, progress: Progress, out_dir: Path, what: str = "bench") -> int:
    """Exit status: 1 if a section failed, 3 if a check failed (each named on stderr), 0
    otherwise; the report is written either way. Targets are reported, never judged here."""
    progress(f"report: {out_dir / 'report.md'}")
    failed = [o.name for o in outcomes if o.status == "failed"]
    if failed:
        progress(f"{what} FAILED: {', '.join(failed)}")
        return 1
    checks = [f"{o.name}: {c.name}" for o in outcomes for c in o.checks if not c.passed]
    total = sum(len(o.checks) for o in outcomes)
    missed = sum(1 for o in outcomes for t in o.targets if t.met is False)
    targets = sum(len(o.targets) for o in outcomes)
    if checks:
        progress(f"{what} FAILED: {len(checks)} of {total} checks failed: {', '.join(checks)}")
        return 3
    progress(f"{what} passed: all {total} checks hold; {targets - missed} of {targets} targets "
             "met (see the targets table)")
    return 0


def command_line(args) -> str:
    """The bench command that reproduces this run (output folder aside)."""
    return " ".join(filter(None, ["torquebench bench", "--quick" if args.quick else "",
                                  f"--robot {args.robot}" if args.robot else "",
                                  f"--sections {args.sections}" if args.sections else "",
                                  "--full" if args.full else "",
                                  "--no-video" if args.no_video else ""]))


def machine() -> dict:
    """What the timings were measured on: CPU model, cores, platform, Python."""
    cpu = platform.processor() or platform.machine()
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.is_file():
        names = [line.split(":", 1)[1].strip() for line in cpuinfo.read_text().splitlines()
                 if line.startswith("model name")]
        cpu = names[0] if names else cpu
    return {"cpu": cpu, "cores": os.cpu_count(), "platform": platform.platform(terse=True),
            "python": platform.python_version()}
