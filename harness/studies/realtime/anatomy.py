"""Where a warm re-plan's time goes (the speed bars), on the random scenarios.

    .venv/bin/python -m harness.studies.realtime.anatomy [--scenarios 20] [--seed 2026]
        [--split | --polish]

1. Algorithm 2 with the penalty loop (compiled) on the planning bench's random
   scenarios; for every warm re-plan: its solver calls, their iterations and CPU time, the
   share of the re-plan spent in them, the calls that ran to the warm iteration cap and
   the penalty weight each call solved with.
2. Fixed and per-iteration cost of one warm solve on the paper scenario (re-plan at
   t = 0.71 s): the same start solved with fatrop (primal start), IPOPT, sqpmethod and
   feasiblesqp (the real-time iterations' feasible SQP; primal-dual) capped at 0, 1 and 5
   iterations and at the warm cap, CPU median of 20 calls
   each, with the status each ended with; and, per solver, the NLP solved again from the
   point its capped solve returned (its own solution where that converged): the floor of
   any warm start.
--split: the planner with the split energy quadrature (random_scenarios.SPLIT); --polish:
the default's with its cold plans polished (random_scenarios.polished: the re-plans start
warm from a polished plan's motion; section 2, one warm solve, is the default's). Section 1
also prints the replayed energy of the feasible executed motions, summed, and how many were
infeasible.
"""

from __future__ import annotations

import collections
import json
import os
import time

import numpy as np

from harness.plan.arm_config import motion_scenario, planner_config
from harness.robots.arm import Arm
from harness.robots.registry import DEFAULT_ROBOT
from harness.studies.realtime import measure as realtime
from harness.studies.realtime import options as random_scenarios
from planning.formulation.screening import screen
from planning.penalty import backends
from planning.penalty.loop import plan_segment
from planning.penalty.planner import PenaltyLoop
from planning.penalty.solver import Planner
from planning.replanning import execute, forecast_at
from planning.types import Segment


class RecordingPlanner(Planner):
    """A Planner that keeps (warm, iterations, CPU ms, success, alpha) of every solver call,
    grouped by plan_segment call (each begins with Planner.prepare)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.groups: list[list[tuple[bool, int, float, bool, float]]] = []

    def prepare(self, goal) -> None:
        super().prepare(goal)
        self.groups.append([])

    def _solve(self, solvers, goal, warm, segment, rescue=True):
        start = time.thread_time()
        plan = super()._solve(solvers, goal, warm, segment, rescue)
        self.groups[-1].append((warm is not None, plan.iterations,
                                1e3 * (time.thread_time() - start), plan.success, segment[5]))
        return plan


def replans(baseline, config, setup: realtime.Setup) -> dict:
    """Section 1: every warm re-plan of Algorithm 2 on the random scenarios, call by call."""
    planner, per_replan = RecordingPlanner(baseline, config), []
    plant, executed, infeasible, cold = Arm.of(DEFAULT_ROBOT).scene, 0.0, 0, []
    for case in realtime.scenarios(baseline, config, setup):
        planner.groups.clear()
        run = execute(PenaltyLoop(planner), case)
        energy, feasible = realtime.replayed_energy(plant, baseline, run, case, config)
        if feasible:
            executed += energy
        infeasible += not feasible
        cold.append(run.solve_cpu_ms[0])
        replanned = len(run.solve_cpu_ms) - 1  # the cold plan's groups come first
        warm_groups = planner.groups[len(planner.groups) - replanned:]
        per_replan += [{"cpu_ms": ms, "calls": calls}
                       for ms, calls in zip(run.solve_cpu_ms[1:], warm_groups, strict=True)]
    cpu = np.array([r["cpu_ms"] for r in per_replan])
    solver = np.array([sum(c[2] for c in r["calls"]) for r in per_replan])
    calls = [c for r in per_replan for c in r["calls"]]
    capped = [c for c in calls if c[0] and c[1] >= config.penalty.warm_max_iterations]
    return {
        "executed_energy_J_sum_of_feasible": executed, "infeasible_executions": infeasible,
        "cold_cpu_ms": realtime.distribution(cold),
        "replans": len(per_replan),
        "replan_cpu_ms": realtime.distribution(cpu),
        "solver_share_of_cpu": float(solver.sum() / cpu.sum()),
        "solver_calls_per_replan": dict(sorted(collections.Counter(
            len(r["calls"]) for r in per_replan).items())),
        "iterations_per_replan": realtime.distribution(
            [sum(c[1] for c in r["calls"]) for r in per_replan]),
        "first_call_iterations": realtime.distribution(
            [r["calls"][0][1] for r in per_replan if r["calls"]]),
        "warm_calls_at_cap": len(capped),
        "calls_at_cap_by_alpha": _by_alpha(capped),
        "calls_by_alpha": _by_alpha(calls),
    }


def _by_alpha(calls) -> dict:
    return {f"{alpha:g}": n for alpha, n in sorted(collections.Counter(c[4] for c in calls).items())}


def call_costs(baseline, config) -> dict:
    """Section 2: CPU of one warm solve capped at 0, 1, 5 iterations and at the warm cap, per
    solver, and of the same NLP solved again from the point that returned."""
    planner = Planner(baseline, config)
    scenario, t = motion_scenario(Arm.of(DEFAULT_ROBOT)), 0.71
    forecast0 = forecast_at(scenario.obstacle, 0.0)
    plan, _, _ = plan_segment(planner, Segment(scenario.start, scenario.start_velocity, 0.0,
                                               scenario.duration, scenario.goal, forecast0))
    for time_ in scenario.obstacle.sample_times[:-1:5]:
        if time_ >= t - 1e-9:
            break
        q, qd, _ = plan.trajectory.state(time_)
        new, _, _ = plan_segment(planner, Segment(q[0], qd[0], time_, scenario.duration - time_,
                                                  scenario.goal,
                                                  forecast_at(scenario.obstacle, time_)),
                                 warm=plan)
        plan = new if new.success else plan
    duration = scenario.duration - t
    q, qd, _ = plan.trajectory.state(t)
    reference = plan.trajectory.restrict(t, duration)
    forecast = forecast_at(scenario.obstacle, t)
    subset = screen(forecast, reference, config.geometry, config.threshold,
                    config.obstacle_slots).subset
    solvers = planner._relaxed_for(scenario.goal)
    nlp = solvers.nlp
    args = {"p": planner.parameters(q[0], qd[0], duration, scenario.goal, subset, t,
                                    reference, plan.penalty_weight)}
    args["lbg"], args["ubg"] = planner.bounds(scenario.goal, nlp)
    start = planner._warm_start(plan, t, duration, nlp, args["p"])
    problem = {"x": nlp.x, "p": nlp.p, "f": nlp.f, "g": nlp.g}
    out = {}
    for plugin in ("fatrop", "ipopt", "sqpmethod", "feasiblesqp"):
        for cap in (0, 1, 5, config.penalty.warm_max_iterations):
            solver = backends.solver(f"anatomy_{plugin}_{cap}", plugin, problem,
                                     nlp.lbg == nlp.ubg, warm=True, max_iter=cap,
                                     hessian="exact", compile_code=True)
            given = {"x0": start["x0"]} if plugin == "fatrop" else start
            out[f"{plugin}, cap {cap}"], solution = _timed(solver, args, given)
        # the floor of a warm start: the same NLP solved again from the point the solve at the
        # warm cap returned (fatrop from its primal point, the others also from its multipliers)
        own = {"x0": solution["x"]}
        if plugin != "fatrop":  # the others take multipliers
            own |= {"lam_g0": solution["lam_g"], "lam_x0": solution["lam_x"]}
        out[f"{plugin}, again from its returned point"], _ = _timed(solver, args, own)
    return out


def _timed(solver, args: dict, start: dict) -> tuple[dict, dict]:
    """Iterations, success, objective and CPU median of 20 calls from one start point; the
    solution."""
    times = []
    for _ in range(20):
        begin = time.thread_time()
        result = solver(**args, **start)
        times.append(1e3 * (time.thread_time() - begin))
    stats = backends.stats(solver, args, result)
    return {"iterations": stats.iterations, "success": stats.success, "status": stats.status,
            "objective": float(result["f"]), "cpu_ms_median": float(np.median(times))}, result


def main() -> None:
    options = random_scenarios.parser(__doc__)
    variant = options.add_mutually_exclusive_group()
    variant.add_argument("--split", action="store_true")
    variant.add_argument("--polish", action="store_true")
    args = options.parse_args()
    baseline = Arm.of(DEFAULT_ROBOT).nominal
    config = planner_config(Arm.of(DEFAULT_ROBOT), compile_code=True,
                            **(random_scenarios.SPLIT if args.split else {}))
    if args.polish:
        config = random_scenarios.polished(config)
    setup = random_scenarios.setup(args)
    print(json.dumps({"call_costs": call_costs(baseline, config)}, indent=1))
    print(json.dumps({"replans": replans(baseline, config, setup)}, indent=1))
    print("load average", os.getloadavg())


if __name__ == "__main__":
    main()
