"""The segment planner a configuration asks for (planning.types.SegmentPlanner), chosen
once: Algorithm 2 and its callers take what this returns and never look inside."""

from __future__ import annotations

import dataclasses

from identification.torque_model import TorqueModel
from planning.anytime.planner import AnytimePlanner
from planning.bank.planner import BankPlanner
from planning.config import JSON_NAMES, PlannerConfig, Scenario, nominal_iteration_ms
from planning.globalsearch.planner import GlobalSearchPlanner
from planning.offline import Offline
from planning.penalty.planner import PenaltyLoop
from planning.penalty.polish import Polished
from planning.penalty.solver import Planner
from planning.replanning import execute
from planning.result import PlanResult, evaluate
from planning.types import SegmentPlanner


def uses_anytime(config: PlannerConfig) -> bool:
    """Whether segments are planned by the anytime SQP: config.replanner "anytime", except with
    the split quadrature (its breaks settle over re-solves, the penalty loop's rounds) and
    with real-time iterations (a feasible-SQP step of the penalty NLP), which keep the
    penalty loop."""
    return config.replanner == "anytime" and config.energy_quadrature != "split" and \
        config.penalty.replan_iterations is None


def segment_planner(model: TorqueModel, config: PlannerConfig,
                    solver: Planner | None = None) -> SegmentPlanner:
    """The anytime SQP (uses_anytime) or the paper's penalty loop for this model and
    configuration; the anytime SQP's cold plans polished by the penalty loop with
    config.penalty.polish (the penalty loop polishes its own). solver: the penalty loop's NLP
    solver of this model and configuration if one is built already (its builds reused)."""
    solver = Planner(model, config) if solver is None else solver
    if not uses_anytime(config):
        return PenaltyLoop(solver)
    planner = anytime = AnytimePlanner(model, config)
    planner = Polished(planner, solver) if config.penalty.polish else planner
    if config.bank.size > 1:  # the global search's plans seed the bank
        return BankPlanner(planner, anytime.anytime, GlobalSearchPlanner(
            planner, model, config, bank=True) if config.global_search.enabled else None)
    return GlobalSearchPlanner(planner, model, config) if config.global_search.enabled \
        else planner


def other_method(config: PlannerConfig) -> PlannerConfig | None:
    """The configuration planning by the other method (the penalty loop for the anytime SQP
    and back), None if there is none: the anytime SQP is no fallback with the split quadrature
    (its breaks settle in the penalty loop only)."""
    if uses_anytime(config):
        return dataclasses.replace(config, replanner="penalty")
    if config.energy_quadrature == "split":
        return None
    return dataclasses.replace(config, replanner="anytime").with_penalty(replan_iterations=None)


def offline_planner(model: TorqueModel, config: PlannerConfig,
                    solver: Planner | None = None) -> Offline:
    """segment_planner's planner whose cold plans run to convergence and fall back to the
    other method's (other_method; planning.offline): for a plan that need not be real time."""
    solver = Planner(model, config) if solver is None else solver
    other = other_method(config)
    return Offline(segment_planner(model, config, solver),
                   None if other is None else segment_planner(model, other, solver),
                   None if other is None else method_name(other))


def method_name(config: PlannerConfig) -> str:
    """PLAN.json's name of the method planning segments under this configuration: "sqp"
    (the anytime SQP) or "fatrop" (the penalty loop)."""
    return JSON_NAMES["anytime" if uses_anytime(config) else "penalty"]


def executed(model: TorqueModel, config: PlannerConfig, scenario: Scenario,
             solver: Planner | None = None, replan: bool = True, realtime: bool = False,
             either: bool = False) -> tuple[PlannerConfig, PlanResult]:
    """Algorithm 2 on the scenario, checked (planning.result.evaluate), and the configuration
    that planned it. Unless realtime the first plan is offline (offline_planner), and a plan
    followed throughout (replan False) that is not feasible is planned by the other method
    too and kept if that one is: found wherever either method finds one (its forecast at
    t = 0, the obstacle standing still, can hide what the motion meets); so is an execution
    with re-plans if `either` (the method not asked for by name). The budgets count CPU if
    realtime, and the motion then runs in real time (execute's paced), else SQP iterations
    of the arm's nominal cost (nominal_iteration_ms)."""
    config = config.with_anytime(iteration_ms=None if realtime else
                                 nominal_iteration_ms(config.geometry.dof))
    solver = Planner(model, config) if solver is None else solver
    make = segment_planner if realtime else offline_planner
    result = evaluate(execute(make(model, config, solver), scenario, replan=replan,
                              paced=realtime), scenario, model, config)
    other = other_method(config)
    if result.feasible or (replan and not either) or realtime or other is None:
        return config, result
    fallback = evaluate(execute(offline_planner(model, other, solver), scenario, replan=replan),
                        scenario, model, other)
    return (other, fallback) if fallback.feasible else (config, result)
