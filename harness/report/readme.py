"""Copy a bench run's headline into README.md.

    python -m harness.report.readme [BENCH_DIR] [README]

Replaces (or appends) the README sections "## Latest benchmark" (the headline
table of BENCH_DIR/report.json) and "## Reading the report" (fixed text);
everything else in the README is left as it is.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

from harness.io import write_text
from harness.report.headline import headline_markdown

READING = """\
`torquebench bench --out DIR` (or `make bench`, DIR = `bench-out`) writes:

- `DIR/report.md`: one section per stage in data-flow order (identification,
  planning, replay, closeloop), each with its tables and figures. A stage that
  raised is marked **FAILED** with its error and the command exits 1; a stage
  whose code does not exist yet says "Section not available yet".
- `DIR/report.json`: the same as data. `headline` holds every headline number
  by section; `sections.<name>` holds `status` (`ok`, `failed`, `not
  available`), `seconds`, `results`, `figures` and `error`.
- `DIR/headline.md`: the table above; `python -m harness.report.readme DIR`
  copies it into this README.
- `DIR/figures/*.png` and, where OpenGL rendering works (`MUJOCO_GL=egl`),
  `DIR/replay_<plan>.mp4`.

How to read the replay numbers: each plan is executed in MuJoCo through the
motor actuators by Pinocchio feedforward + PD at the 0.5 ms timestep, while
the obstacle moves as a mocap body. `energy_replayed_J` is ∫|Σ τᵢ q̇ᵢ| dt of
the torques the actuators actually applied; `energy_planned_J` is the
planner's own figure, so their gap is the cost of the model's error plus
tracking. `min_clearance_m` is the smallest distance from the obstacle centre
to the link segments (the paper's d1, d2, compared with the threshold λ);
`surface_clearance_m` is MuJoCo's `mj_geomDistance` between the link capsules
and the obstacle sphere. `energy_ratio_identified_over_closed_form_*` above 1
means the identified model's plan costs more than the closed-form plan (the
paper's Fig. 11 found slightly more). Acceptance per plan: tracking RMS ≤ 1
mrad, replayed energy within 2 % of planned, clearance ≥ λ − 5 mm.
"""


def replace_section(text: str, title: str, body: str) -> str:
    """text with the '## title' section's body replaced, or the section appended."""
    section = f"## {title}\n\n{body.strip()}\n"
    pattern = re.compile(rf"^## {re.escape(title)}\n.*?(?=^## |\Z)", re.S | re.M)
    if pattern.search(text):
        return pattern.sub(lambda _: section + "\n", text, count=1).rstrip() + "\n"
    return (text.rstrip() + "\n\n" if text.strip() else "") + section


KEY_NUMBERS = (  # the README's compact table; the full one is DIR/headline.md
    r"noise 5 %: (sparse|oracle) rel err",
    r"energy_(planned|replayed)_J$", r"energy_ratio_identified", r"min_clearance_m$",
    r"tracking_rms_rad$", r"\.acceptance$",
    r"^replan_(median|p95)_ms$", r"^cold_plan_median_ms$",
    r"^(friction|payload)\.[^.]*\.?error_(before|after)$",
)


def key_numbers(numbers: dict[str, dict]) -> dict[str, dict]:
    """The headline rows matching KEY_NUMBERS."""
    return {section: {k: v for k, v in values.items()
                      if any(re.search(p, k) for p in KEY_NUMBERS)}
            for section, values in numbers.items()}


def _pct(values) -> str:
    return ", ".join(f"{100 * v:.3f} %" for v in values)


def _get(headline: dict, section: str, key: str):
    return headline.get(section, {}).get(key)


def glance(headline: dict, sections: dict | None = None) -> str:
    """The README's answer to the one question, in plain rows; missing numbers are skipped."""
    rows = []
    ident = ((sections or {}).get("identification") or {}).get("results") or {}
    sparse = _get(headline, "identification", "noise 5 %: sparse rel err")
    oracle = _get(headline, "identification", "noise 5 %: oracle rel err")
    if sparse and oracle:
        rows.append(("Identified torque, 5 % noise: held-out rel. RMS error per joint "
                     "(coupled sparse; oracle = WLS on Pinocchio's base regressor)",
                     f"{_pct(sparse)}; oracle {_pct(oracle)}"))
    bar = (ident.get("acceptance_5pct") or {}).get("ratio_to_true_support")
    if bar:
        rows.append(("Same, relative to WLS on exactly the true terms (what a perfect selector "
                     "achieves; the dense oracle also fits the truth's zero parameters)",
                     ", ".join(f"{v:.3f} x" for v in bar)))
    robust = (ident.get("acceptance_5pct") or {})
    if "every_draw_within_1.25x_oracle" in robust:
        rows.append(("20 independent 5 % noise draws: every draw within 1.25 x the oracle on every "
                     "joint?", "yes" if robust["every_draw_within_1.25x_oracle"] else
                     "no (median draw: " + ("yes" if robust.get("median_draw_within_1.25x_oracle")
                                            else "no") + "; see report)"))
    pct = _get(headline, "planning", "identified_vs_pinocchio_energy_pct")
    if pct is not None:
        rows.append(("Paper scenario: energy of the identified-model plan vs the closed-form plan "
                     "(both evaluated with Pinocchio)", f"{pct:+.3f} %"))
    ratio = _get(headline, "replay", "energy_ratio_identified_over_closed_form_replayed")
    if ratio is not None:
        rows.append(("Same two plans replayed in MuJoCo: energy ratio identified / closed-form",
                     f"{ratio:.5f}"))
    clear = [v for k, v in headline.get("replay", {}).items() if k.endswith(".min_clearance_m")]
    if clear:
        rows.append(("Smallest link-obstacle clearance kept in any MuJoCo replay (threshold 80 mm)",
                     f"{1000 * min(clear):.1f} mm"))
    planning = headline.get("planning", {})
    med = next((v for k, v in planning.items() if k.startswith("synthetic_replan_median_ms")), None)
    p95 = planning.get("synthetic_replan_p95_ms")
    if med is not None and p95 is not None:
        rows.append(("Warm re-plan (obstacle one sample further), median / p95", f"{med:.1f} / {p95:.1f} ms"))
    actual = [v for k, v in planning.items() if k.endswith(".replan_ms_median")]
    if actual:
        rows.append(("Re-plans the scenarios actually made (first one sees the obstacle move), "
                     "median per scenario", ", ".join(f"{v:.1f}" for v in actual) + " ms"))
    bound = _get(headline, "planning", "net_work_bound_J")
    paper = _get(headline, "planning", "parametrization.quartic, N=10 (paper).free_true_energy_J")
    if bound is not None and paper is not None:
        rows.append(("No-obstacle optimum: true energy of the paper's quartic/N=10 plan vs the "
                     "net-work lower bound (= minimum jerk)", f"{paper:.4f} J vs {bound:.4f} J"))
    before = _get(headline, "closeloop", "friction.pinocchio.error_before")
    after = _get(headline, "closeloop", "friction.pinocchio.error_after")
    if before and after:
        rows.append(("Closing the loop, friction plant: Pinocchio model's held-out error before -> "
                     "after adding the named effects", f"{_pct(before)} -> {_pct(after)}"))
    verdict = headline.get("acceptance", {})
    if verdict:
        rows.append(("Acceptance checks of all issues, failed", verdict["checks failed"].strip("*")
                     + (f" ({verdict['failed']})" if verdict.get("failed") else "")))
    if not rows:
        return ""
    return "\n".join(["| question | measured |", "|---|---|", *(f"| {a} | {b} |" for a, b in rows)])


def latest_benchmark(report: dict, source: str) -> str:
    """The '## Latest benchmark' body: provenance line and the headline table."""
    state = "all sections ok" if report.get("ok") else "**some sections failed**"
    missing = [n for n, s in report.get("sections", {}).items() if s["status"] == "not available"]
    note = f"; not available yet: {', '.join(missing)}" if missing else ""
    quick = " --quick" if report.get("quick") else ""
    return (f"From `torquebench bench{quick}` ({source}/report.json, "
            f"{report.get('elapsed_s', 0):.0f} s, {state}{note}); every headline number is in "
            f"`{source}/headline.md` and `report.json`.\n\n"
            + glance(report.get("headline", {}), report.get("sections")) + "\n\nKey numbers by section:\n\n"
            + headline_markdown(key_numbers(report.get("headline", {}))))


def update_readme(bench_dir: Path, readme: Path) -> None:
    """Rewrite the two report sections of readme from bench_dir/report.json."""
    report = json.loads((bench_dir / "report.json").read_text())
    text = readme.read_text() if readme.exists() else ""
    text = replace_section(text, "Latest benchmark", latest_benchmark(report, bench_dir.name))
    text = replace_section(text, "Reading the report", READING)
    write_text(readme, text)


def main(argv: list[str]) -> int:
    bench_dir = Path(argv[0]) if argv else Path("bench-out")
    readme = Path(argv[1]) if len(argv) > 1 else Path("README.md")
    update_readme(bench_dir, readme)
    print(f"updated {readme} from {bench_dir / 'report.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
