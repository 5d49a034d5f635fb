"""`torquebench bench --out DIR`: the whole pipeline on the default robot, one report.

Sections run in data-flow order (identification -> planning -> replay ->
closeloop); each is imported on demand, so a section not written yet is
reported as "not available" and a section that raises is reported as failed
with its message, and the command exits 1 at the end. Progress goes to stderr
as one line per event with the elapsed wall time.
"""

from __future__ import annotations

import importlib
import sys
import threading
import time
import traceback
from contextlib import contextmanager
from pathlib import Path

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
    p.set_defaults(func=run)


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
                 robot: str = DEFAULT_ROBOT):
    """All sections of robot in order, each fed what the previous ones produced."""
    outcomes, raws = [], {}
    for name in SECTIONS if robot == DEFAULT_ROBOT else ARM_SECTIONS:
        kwargs = {"robot": robot} if name in ARM_SECTIONS else {}
        if name == "planning" and raws.get("identification", {}).get("model") is not None:
            kwargs["identified_model"] = raws["identification"]["model"]
        if name == "replay":
            kwargs = {"plans": raws.get("planning", {}).get("plans") or {}, "video": video}
        if name == "arm_replay":
            kwargs.update(plans=raws.get("arm_planning", {}).get("plans") or {}, video=video)
        outcome, raws[name] = run_section(name, progress, out_dir, quick, **kwargs)
        outcomes.append(outcome)
    return outcomes, raws.get("planning", {}).get("plans") or {}


def run(args) -> int:
    out_dir = Path(args.out)
    if args.robot not in ROBOTS:
        raise UserError(f"unknown robot '{args.robot}' (known: {', '.join(sorted(ROBOTS))})")
    if out_dir.exists() and not out_dir.is_dir():
        raise UserError(f"--out {out_dir} exists and is not a directory")
    out_dir.mkdir(parents=True, exist_ok=True)
    progress = Progress()
    progress(f"bench on '{args.robot}' -> {out_dir}{' (quick)' if args.quick else ''}")
    outcomes, plans = run_pipeline(out_dir, args.quick, not args.no_video, progress, args.robot)
    numbers = headline({o.name: o.results for o in outcomes if o.status == "ok"}, plans)
    meta = {"robot": args.robot, "quick": bool(args.quick), "elapsed_s": progress.elapsed}
    write_report(out_dir, outcomes, numbers, meta)
    failed = [o.name for o in outcomes if o.status == "failed"]
    missing = [o.name for o in outcomes if o.status == "not available"]
    progress(f"report: {out_dir / 'report.md'}")
    if missing:
        progress(f"warning: sections not available yet: {', '.join(missing)}")
    if failed:
        progress(f"bench FAILED: {', '.join(failed)}")
        return 1
    return 0
