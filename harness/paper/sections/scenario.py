"""The paper's planning scenario on its own arm (Section III.G, Figs. 9-11), in the paper's
formulation: quartic joint polynomials, eq. (18)'s N = 10 energy samples and a free end
velocity (`plan --free-end`), with the closed-form and the identified model; beside them
the default planner (true energy, rest to rest) on the same scenario."""

from __future__ import annotations

from harness.paper.planning.scenario import paper_scenario
from harness.paper.planning.variants import PAPER
from harness.plan.arm_config import planner_config
from harness.plan.scoring import plan_checks, reproducible, summary
from harness.report.results import Context, Row, SectionResult, Target
from harness.robots.baseline import PinocchioModel
from planning.planners import segment_planner
from planning.replanning import execute
from planning.result import evaluate, to_json

IDENTIFIED_TARGET = 0.02  # identified plan's true energy within 2 % of the closed form's


def run(ctx: Context, models: dict) -> SectionResult:
    baseline = next(m for m in models.values() if isinstance(m, PinocchioModel))
    paper = PAPER.config(planner_config(ctx.arm, rest_at_goal=False))
    default = reproducible(planner_config(ctx.arm))
    scenario = paper_scenario()
    runs = {f"paper_{name}": (model, paper) for name, model in models.items()}
    runs["default_pinocchio"] = (baseline, default)
    results, plans, checks = {}, {}, []
    for name, (model, config) in runs.items():
        executed = evaluate(execute(segment_planner(model, config), scenario), scenario, model, config)
        results[name] = summary(executed, baseline, config)
        plans[name] = to_json(executed, scenario, config, name.split("_", 1)[1])
        checks += plan_checks(name, results[name], config.threshold, config.rest_at_goal)[0]
    md = ["The paper's scenario (q0 = (pi/2, pi/5, -pi/4), goal (-pi/2, 2 pi/5, -pi/3), 2 s, "
          "the obstacle from (0.15, 0.40, 0.22) to (0.18, -0.35, 0.28) m, lambda = 0.08 m). "
          "`paper_*`: the paper's formulation (N = 10, free end velocity: `plan --free-end`); "
          "`default_pinocchio`: the default planner (Gauss N = 20, rest to rest).", "",
          "| plan | energy, own model (J) | true energy (J) | min clearance (mm) | re-plans | "
          "end speed (rad/s) |", "|---|---|---|---|---|---|"]
    md += [f"| {n} | {s['energy_J']:.4f} | {s['true_energy_J']:.4f} | "
           f"{1e3 * s['min_clearance_m']:.1f} | {s['replans']} | {s['end_speed_rad_s']:.2f} |"
           for n, s in results.items()]
    targets, headline = [], []
    if "paper_identified" in results:
        e_id, e_cf = (results[k]["true_energy_J"] for k in ("paper_identified", "paper_pinocchio"))
        targets.append(Target("paper scenario: identified plan's true energy against the "
                              "closed-form plan's", 100 * abs(e_id / e_cf - 1),
                              100 * IDENTIFIED_TARGET, "%"))
        headline.append(Row("Paper scenario (paper's formulation, free end): true energy of the "
                            "identified vs the closed-form model's plan",
                            f"{e_id:.4f} J vs {e_cf:.4f} J ({100 * (e_id / e_cf - 1):+.2f} %)"))
    return SectionResult("\n".join(md), results, checks, targets, headline,
                         outputs={"plans": plans})
