"""Copy a bench run's headline into README.md.

    python -m harness.report.readme [BENCH_DIR] [README]

Replaces (or appends) the README sections "## Latest benchmark" (the headline table of
BENCH_DIR/report.json and the run's timings, labelled with the machine and command that
produced them) and "## Reading the report"; everything else in the README is left as it is.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

from harness.io import write_text
from harness.report.headline import MAX_ROWS, headline_markdown


def reading() -> str:
    """The README's '## Reading the report' text, its bars read from the code that checks them."""
    from harness.sections.replay import CLEARANCE_MARGIN, ENERGY_TOLERANCE, TRACKING_LIMIT

    return f"""\
`torquebench bench --out DIR` (or `make bench`, DIR = `bench-out`) writes:

- `DIR/report.md`: the headline (at most {MAX_ROWS} rows: the question answered), then one
  section per stage in data-flow order (identification, planning, replay, closeloop, ...),
  each with its tables and figures. A stage that raised is marked **FAILED** with its error;
  a stage whose code does not exist yet says "Section not available yet".
- `DIR/report.json`: the same as data. `headline.rows` holds the headline (question, measured
  text, the numbers behind it), `headline.acceptance` every acceptance check that failed;
  `sections.<name>` holds `status` (`ok`, `failed`, `not available`), `seconds`, `results`,
  `figures` and `error`; `machine` and `timing` say where and when it ran. Two runs with the
  same configuration write the same report.json apart from timings (keys named `seconds`,
  `*_s`, `*_ms`, `timing`; checked in tests/test_bench.py).
- `DIR/headline.md`: the headline table; `python -m harness.report.readme DIR` copies it
  into this README with the run's timings, labelled with the machine and command.
- `DIR/figures/*.png` and, where OpenGL rendering works (`MUJOCO_GL=egl`),
  `DIR/replay_<plan>.mp4`.

Exit status: 0 when every section ran and every acceptance check passed, 1 when a section
failed, 3 when an acceptance check failed (each one named on stderr); the report is written
in every case. `bench --sections a,b` runs only those sections.

How to read the replay numbers: each plan is executed in MuJoCo through the motor actuators
by Pinocchio feedforward + PD at the 0.5 ms timestep, while the obstacle moves as a mocap
body. The replayed energy is the integral of |sum tau_i qd_i| dt of the torques the actuators
actually applied; the planned energy is the planner's own figure, so their gap is the cost of
the model's error plus tracking. The clearance is the smallest distance from the obstacle
centre to the link segments (the paper's d1, d2, compared with the threshold lambda).
Acceptance per plan: tracking RMS <= {1e3 * TRACKING_LIMIT:g} mrad, replayed energy within
{100 * ENERGY_TOLERANCE:g} % of planned, clearance >= lambda - {1e3 * CLEARANCE_MARGIN:g} mm.
"""


def replace_section(text: str, title: str, body: str) -> str:
    """text with the '## title' section's body replaced, or the section appended."""
    section = f"## {title}\n\n{body.strip()}\n"
    pattern = re.compile(rf"^## {re.escape(title)}\n.*?(?=^## |\Z)", re.S | re.M)
    if pattern.search(text):
        return pattern.sub(lambda _: section + "\n", text, count=1).rstrip() + "\n"
    return (text.rstrip() + "\n\n" if text.strip() else "") + section


def _planning_speed(sections: dict) -> list[tuple[str, str]]:
    speed = ((sections.get("planning") or {}).get("results") or {}).get("speed") or {}
    rows = []
    if "cold_median_ms" in speed:
        rows.append(("Cold plan, paper scenario (median)", f"{speed['cold_median_ms']:.1f} ms"))
    if "replan_median_ms" in speed and "replan_p95_ms" in speed:
        rows.append(("Warm re-plan, obstacle one sample further (median / p95)",
                     f"{speed['replan_median_ms']:.1f} / {speed['replan_p95_ms']:.1f} ms"))
    if "replan_cpu_median_ms" in speed:
        rows.append(("Same, CPU time of the solving thread (median)",
                     f"{speed['replan_cpu_median_ms']:.1f} ms"))
    return rows


def timings(report: dict) -> str:
    """The run's timings, labelled with the machine and the command that produced them."""
    sections = report.get("sections") or {}
    rows = _planning_speed(sections)
    rows += [(f"Section {name}", f"{s['seconds']:.1f} s") for name, s in sections.items()
             if s.get("status") == "ok"]
    timing, machine = report.get("timing") or {}, report.get("machine") or {}
    rows.append(("Whole run", f"{timing.get('elapsed_s', 0.0):.0f} s"))
    where = (f"{machine.get('cpu', 'unknown CPU')}, {machine.get('cores', '?')} cores, "
             f"{machine.get('platform', '?')}, Python {machine.get('python', '?')}")
    load = timing.get("load_average_at_start")
    load = f", load average {load:.1f} at the start" if load is not None else ""
    return "\n".join([f"Wall-clock times of that run (`{report.get('command', 'torquebench bench')}`"
                      f", started {timing.get('started_utc', '?')}) on {where}{load}; they depend "
                      "on the machine and its load, the numbers above do not.", "",
                      "| timing | measured |", "|---|---|", *(f"| {a} | {b} |" for a, b in rows)])


def latest_benchmark(report: dict, source: str) -> str:
    """The '## Latest benchmark' body: provenance, the headline and the run's timings."""
    state = "all sections ok" if report.get("ok") else "**some sections failed**"
    missing = [n for n, s in report.get("sections", {}).items() if s["status"] == "not available"]
    note = f"; not available yet: {', '.join(missing)}" if missing else ""
    return (f"From `{report.get('command', 'torquebench bench')}` ({source}/report.json, "
            f"{state}{note}); each section's details are in `{source}/report.md`.\n\n"
            + headline_markdown(report.get("headline") or {}) + "\n\n" + timings(report))


def update_readme(bench_dir: Path, readme: Path) -> None:
    """Rewrite the two report sections of readme from bench_dir/report.json."""
    report = json.loads((bench_dir / "report.json").read_text())
    text = readme.read_text() if readme.exists() else ""
    text = replace_section(text, "Latest benchmark", latest_benchmark(report, bench_dir.name))
    text = replace_section(text, "Reading the report", reading())
    write_text(readme, text)


def main(argv: list[str]) -> int:
    bench_dir = Path(argv[0]) if argv else Path("bench-out")
    readme = Path(argv[1]) if len(argv) > 1 else Path("README.md")
    update_readme(bench_dir, readme)
    print(f"updated {readme} from {bench_dir / 'report.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
