"""`torquebench bench --out DIR`: the whole pipeline on the default robot, one report.

Sections run in data-flow order (identification -> planning -> replay ->
closeloop); each is imported on demand, so a section not written yet is
reported as "not available" and a section that raises is reported as failed
with its message. The report is always written; the command then exits 1 if a
section failed, 3 if an acceptance check failed (naming each on stderr), else 0. Progress goes to stderr
as one line per event with the elapsed wall time.
"""

from __future__ import annotations

import importlib
import os
import platform
import sys
import threading
import time
import traceback
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path

from harness import interrupt
from harness.errors import UserError
from harness.report.headline import headline
from harness.report.writer import SectionOutcome, write_report
from harness.robots.registry import DEFAULT_ROBOT, ROBOTS

SECTIONS = ("identification", "planning", "replay", "closeloop", "arm_identification",
            "real_data")
ARM_SECTIONS = ("arm_identification", "arm_planning", "arm_replay",
                "arm_closeloop")  # on another robot than the default
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
        "bench", help="run the whole benchmark on the default robot and write a report",
        description="Data, denoising, identification, Pinocchio comparison, planning with both "
        "models, MuJoCo replay and close-the-loop; writes DIR/report.md, DIR/report.json, "
        "DIR/headline.md and DIR/figures/*.png.",
    )
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--quick", action="store_true", help="smaller data and fewer sweeps")
    p.add_argument("--robot", default=DEFAULT_ROBOT,
                   help=f"registered robot; {DEFAULT_ROBOT} (default): the paper reproduction and "
                   "every section; another arm: identification from its kinematics, planning and "
                   "replay, closing the loop")
    p.add_argument("--no-video", action="store_true", help="do not render replay videos")
    p.add_argument("--sections", default=None,
                   help="comma-separated sections to run, in pipeline order (default: all of the "
                   f"robot's: {', '.join(SECTIONS)}; another arm: {', '.join(ARM_SECTIONS)}); "
                   "replay replays the plans of planning, so without it there is nothing to replay")
    p.set_defaults(func=run)


def chosen_sections(robot: str, names: str | None) -> tuple[str, ...]:
    """The robot's sections, restricted to names (comma-separated) in pipeline order."""
    available = SECTIONS if robot == DEFAULT_ROBOT else ARM_SECTIONS
    if names is None:
        return available
    wanted = [n.strip() for n in names.split(",") if n.strip()]
    unknown = [n for n in wanted if n not in available]
    if unknown or not wanted:
        raise UserError(f"--sections: unknown section(s) {', '.join(unknown) or '(none given)'} "
                        f"for robot {robot} (known: {', '.join(available)})")
    return tuple(n for n in available if n in wanted)


def load_section(name: str):
    """The module harness.sections.<name> (for a section grown into a package, its `section`
    module), or None if it does not exist yet."""
    try:
        module = importlib.import_module(f"harness.sections.{name}")
    except ModuleNotFoundError as exc:
        if exc.name != f"harness.sections.{name}":
            raise
        return None
    if hasattr(module, "__path__"):  # a package: its entry point is harness.sections.<name>.section
        return importlib.import_module(f"harness.sections.{name}.section")
    return module


def _error_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".rstrip(": ")


def run_section(name: str, progress: Progress, out_dir: Path, quick: bool,
                **kwargs) -> tuple[SectionOutcome, dict]:
    """Run one section; never raises, the outcome records what happened."""
    try:
        module = load_section(name)
    except Exception as exc:  # a section that fails to import is a failed section
        progress(f"{name}: FAILED to import: {_error_line(exc)}")
        return SectionOutcome(name, "failed", error=_error_line(exc)), {}
    if module is None:
        progress(f"{name}: not available yet, skipped")
        return SectionOutcome(name, "not available"), {}
    progress(f"{name}: started")
    start = time.perf_counter()
    try:
        with progress.heartbeat(name):
            raw = module.run(out_dir, quick=quick, **kwargs)
        if not isinstance(raw, dict):
            raise TypeError(f"section returned {type(raw).__name__}, expected dict")
    except Exception as exc:
        seconds = time.perf_counter() - start
        traceback.print_exc(file=sys.stderr)
        progress(f"{name}: FAILED after {seconds:.1f} s: {_error_line(exc)}")
        return SectionOutcome(name, "failed", seconds, error=_error_line(exc)), {}
    seconds = time.perf_counter() - start
    progress(f"{name}: done in {seconds:.1f} s")
    outcome = SectionOutcome(
        name, "ok", seconds, markdown=str(raw.get("markdown", "")),
        results=raw.get("results") or {}, figures=tuple(str(f) for f in raw.get("figures", [])),
    )
    return outcome, raw


def run_pipeline(out_dir: Path, quick: bool, video: bool, progress: Progress,
                 robot: str = DEFAULT_ROBOT, sections: tuple[str, ...] | None = None):
    """The sections of robot (all, or those given) in order, each fed what the previous ones
    produced."""
    outcomes, raws = [], {}
    for name in sections or chosen_sections(robot, None):
        kwargs = {"robot": robot} if name in ARM_SECTIONS else {}
        if name == "planning" and raws.get("identification", {}).get("model") is not None:
            kwargs["identified_model"] = raws["identification"]["model"]
        if name == "replay":
            kwargs = {"plans": raws.get("planning", {}).get("plans") or {}, "video": video}
        if name == "arm_replay":
            kwargs.update(plans=raws.get("arm_planning", {}).get("plans") or {}, video=video)
        outcome, raws[name] = run_section(name, progress, out_dir, quick, **kwargs)
        interrupt.check()  # Ctrl-C during a section that swallowed it: stop here
        outcomes.append(outcome)
    return outcomes, raws.get("planning", {}).get("plans") or {}


def run(args) -> int:
    out_dir = Path(args.out)
    started = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else None  # other processes' share
    if args.robot not in ROBOTS:
        raise UserError(f"unknown robot '{args.robot}' (known: {', '.join(sorted(ROBOTS))})")
    if out_dir.exists() and not out_dir.is_dir():
        raise UserError(f"--out {out_dir} exists and is not a directory")
    sections = chosen_sections(args.robot, args.sections)
    out_dir.mkdir(parents=True, exist_ok=True)
    progress = Progress()
    progress(f"bench on '{args.robot}' -> {out_dir}{' (quick)' if args.quick else ''}")
    outcomes, plans = run_pipeline(out_dir, args.quick, not args.no_video, progress, args.robot,
                                   sections)
    numbers = headline({o.name: o.results for o in outcomes if o.status == "ok"}, plans)
    meta = {"robot": args.robot, "quick": bool(args.quick), "sections": list(sections),
            "command": command_line(args), "machine": machine(),
            "timing": {"elapsed_s": progress.elapsed, "started_utc": started,
                       "load_average_at_start": load}}
    write_report(out_dir, outcomes, numbers, meta)
    return verdict(outcomes, numbers, progress, out_dir)


def verdict(outcomes, numbers: dict, progress: Progress, out_dir: Path) -> int:
    """Exit status: 1 if a section failed, 3 if an acceptance check failed (each named on
    stderr), 0 otherwise; the report is written either way."""
    failed = [o.name for o in outcomes if o.status == "failed"]
    missing = [o.name for o in outcomes if o.status == "not available"]
    progress(f"report: {out_dir / 'report.md'}")
    if missing:
        progress(f"warning: sections not available yet: {', '.join(missing)}")
    if failed:
        progress(f"bench FAILED: {', '.join(failed)}")
        return 1
    checks = numbers.get("acceptance") or {}
    if checks.get("failed"):
        progress(f"bench FAILED acceptance: {len(checks['failed'])} of {checks['total']} checks "
                 f"failed: {', '.join(checks['failed'])}")
        return 3
    return 0


def command_line(args) -> str:
    """The bench command that reproduces this run (output folder aside)."""
    return " ".join(filter(None, ["torquebench bench", "--quick" if args.quick else "",
                                  f"--robot {args.robot}" if args.robot != DEFAULT_ROBOT else "",
                                  f"--sections {args.sections}" if args.sections else "",
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
