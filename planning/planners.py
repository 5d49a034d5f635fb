"""The segment planner a configuration asks for (planning.types.SegmentPlanner), chosen
once: Algorithm 2 and its callers take what this returns and never look inside."""

from __future__ import annotations

from identification.torque_model import TorqueModel
from planning.anytime.planner import AnytimePlanner
from planning.config import PlannerConfig
from planning.penalty.planner import PenaltyLoop
from planning.penalty.polish import Polished
from planning.penalty.solver import Planner
from planning.types import SegmentPlanner


def uses_anytime(config: PlannerConfig) -> bool:
    """Whether segments are planned by the anytime SQP: config.replanner "anytime", except with
    the split quadrature (its breaks settle over re-solves, the penalty loop's rounds) and
    with real-time iterations (a feasible-SQP step of the penalty NLP), which keep the
    penalty loop."""
    return config.replanner == "anytime" and config.energy_quadrature != "split" and \
        config.penalty.replan_iterations is None


def segment_planner(model: TorqueModel, config: PlannerConfig | None = None,
                    solver: Planner | None = None) -> SegmentPlanner:
    """The anytime SQP (uses_anytime) or the paper's penalty loop for this model and
    configuration; the anytime SQP's cold plans polished by the penalty loop with
    config.penalty.polish (the penalty loop polishes its own). solver: the penalty loop's NLP
    solver of this model and configuration if one is built already (its builds reused)."""
    config = config or PlannerConfig()
    solver = Planner(model, config) if solver is None else solver
    if not uses_anytime(config):
        return PenaltyLoop(solver)
    planner = AnytimePlanner(model, config)
    return Polished(planner, solver) if config.penalty.polish else planner
