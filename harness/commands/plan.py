"""`torquebench plan`: an energy-optimal, obstacle-avoiding trajectory (paper III.G).

The configuration is the robot's (harness.plan.arm_config) with the options given
(harness.plan.options); the motion, the robot's registered one past the Lynxmotion paper
scenario's obstacle path unless given. The plan is written only if it is feasible
(solver converged, goal reached, limits kept, clearance held); otherwise the
command names the problem and exits 2 without writing.
"""

from __future__ import annotations

import argparse
import logging
import re
import sys
from typing import NamedTuple

from harness.commands import SUMMARY, add_chain_option, chain_option
from harness.io import write_json
from harness.plan.anytime_options import add_anytime_options
from harness.plan.arm_config import DURATION, default_obstacle
from harness.plan.limits import vector_text
from harness.plan.messages import (
    BuildNotice,
    default_obstacle_diagnosis,
    default_obstacle_notice,
    fallback_note,
    first_plan_note,
    infeasible,
    search_failure_note,
    torque_diagnosis,
    velocity_diagnosis,
)
from harness.plan.options import config_from_options, scenario_from_options
from harness.plan.trajectory_csv import DEFAULT_RATE, write_trajectory
from harness.robots.resolve import Arm, resolve_arm
from harness.robots.torque_models import read_model, torque_model
from identification.torque_model import TorqueModel
from planning.config import (
    ALIASES,
    REPLANNERS,
    TRUE_ENERGY,
    PenaltyOptions,
    PlannerConfig,
    Scenario,
)
from planning.control import control_trajectory
from planning.errors import PlanningError
from planning.formulation import compiled
from planning.formulation.quadrature import RULES
from planning.penalty.backends import SOLVERS
from planning.penalty.solver import Planner
from planning.planners import executed
from planning.result import PlanResult, closest_link, to_json

OBSTACLE = default_obstacle()  # the default path (the Lynxmotion paper scenario's)
# every option's default is None, left out: the arm's planner_config's, or as its help says


def register(sub) -> None:
    p = sub.add_parser("plan", help=SUMMARY["plan"])
    p.add_argument("--model", required=True, help="MODEL.json or 'pinocchio'")
    p.add_argument("--robot", default=None,
                   help="registered robot or URDF/MJCF path: its links, joint and torque limits and its "
                        "pinocchio baseline (default: the model's robot, else lynxmotion)")
    add_chain_option(p)
    p.add_argument("--start", default=None,
                   help="start angles, one per joint (rad); default: the robot's registered "
                        "motion (on the Lynxmotion the paper's)")
    p.add_argument("--goal", default=None,
                   help="goal angles, one per joint (rad); default: the robot's registered "
                        "motion (on the Lynxmotion the paper's)")
    p.add_argument("--duration", type=float, default=None,
                   help=f"motion time (s, default {DURATION:g})")
    p.add_argument("--obstacle-from", default=None,
                   help="obstacle centre at t = 0 (m); default: the Lynxmotion paper scenario's, "
                        + vector_text(OBSTACLE.start))
    p.add_argument("--obstacle-to", default=None,
                   help="obstacle centre at t = duration (m); default: the Lynxmotion paper "
                        "scenario's, " + vector_text(OBSTACLE.end))
    p.add_argument("--samples", type=int, default=None,
                   help=f"obstacle samples K over the motion (default {OBSTACLE.samples})")
    p.add_argument("--threshold", type=float, default=None,
                   help=f"clearance threshold lambda (m, default {PlannerConfig.threshold:g})")
    p.add_argument("--penalty", type=float, default=None,
                   help="penalty weight alpha (J/m^2 per obstacle sample, default "
                        f"{PlannerConfig.penalty_weight:g})")
    p.add_argument("--energy-samples", type=int, default=None,
                   help="power samples N of the energy objective (default: 20 for gauss, the "
                        "paper's 10 for paper, 21 for simpson, 3 per interval for split)")
    p.add_argument("--energy-quadrature", choices=RULES, default=None,
                   help="where the power is sampled: gauss (Gauss-Legendre, the default: plans "
                        "with the true energy at N = 20), paper (eq. 18, s_i = i/N), simpson, "
                        "split (Gauss between the power's sign changes)")
    p.add_argument("--power-breaks", type=int, default=None,
                   help="split: breaks between the quadrature's intervals, put where the "
                        "power changes sign; --energy-samples must be a multiple of this + 1 "
                        f"(default {PlannerConfig.power_breaks})")
    p.add_argument("--degree", type=int, default=None,
                   help=f"degree of the joint polynomials (4..9, default {PlannerConfig.degree}: "
                        "the paper's)")
    p.add_argument("--power-smoothing", type=float, default=None,
                   help="W; 0 (the default): exact |P| (epigraph), > 0: sqrt(P^2 + eps^2) - eps")
    p.add_argument("--obstacle-sway", default=None,
                   help="sway amplitude vector (m) added to the linear obstacle path as "
                        "sway sin(2 pi periods t / duration) (default: none)")
    p.add_argument("--sway-periods", type=float, default=None,
                   help="sway periods over the motion (default 1)")
    p.add_argument("--torque-limit", default=None,
                   help="per-joint torque limits (N m, one per joint), or 'none'; default: the "
                        "robot MJCF's motor ctrlrange times gear, else the URDF effort limits")
    p.add_argument("--velocity-limit", default=None,
                   help="per-joint velocity limits (rad/s, one per joint), or 'none'; default: "
                        "the URDF's <limit velocity>")
    p.add_argument("--accel-limit", default=None,
                   help="acceleration limit (rad/s^2): one for every joint or one per joint "
                        "(default: none)")
    p.add_argument("--link-radius", default=None,
                   help="capsule radius around every joint-origin segment (m; clearance is to "
                        "its surface; 0: the centre lines, the paper's), or 'collision' (the "
                        "default): capsules fitted to the URDF's collision (else visual) "
                        "meshes, the centre lines on links without (a robot without meshes: "
                        "all its links, as 0)")
    p.add_argument("--trajectory", default=None,
                   help="also write the executed motion at the control rate to this CSV: "
                        "t,q1..qn,qd1..qdn,qdd1..qddn,tau1..taun (s, rad, rad/s, rad/s^2, "
                        "N m: the planning model's feed-forward torque), ending at rest at the "
                        "goal")
    p.add_argument("--rate", type=float, default=None,
                   help="control rate of --trajectory (Hz, default 500)")
    p.add_argument("--solver", choices=SOLVERS, default=None,
                   help="NLP solver (CasADi plugin); ipopt is the paper's (default: fatrop on "
                        "the Lynxmotion, ipopt on other arms)")
    p.add_argument("--starts", type=int, default=None,
                   help="start points of the cold plan (the best is kept; default "
                        f"{TRUE_ENERGY['starts']})")
    p.add_argument("--polish", type=int, default=None,
                   help="the best N distinct cold plans are solved again with the split "
                        "quadrature (breaks at the power's sign changes) and the one that "
                        "spends least kept (0, the default: none)")
    p.add_argument("--polish-samples", type=int, default=None,
                   help="nodes of the polishing quadrature: a multiple of --power-breaks + 1 "
                        f"(default {PenaltyOptions.polish_samples})")
    p.add_argument("--deadline-ms", type=float, default=None,
                   help="ms a re-plan may take (nominal; CPU with --realtime); a later one is "
                        "dropped and the last plan kept, as on a real-time controller (0, the "
                        "default: no deadline; "
                        "the obstacle's sample period is 10 ms)")
    p.add_argument("--replanner", choices=REPLANNERS + tuple(ALIASES), default=None,
                   help="how plans and re-plans are solved: anytime (alias sqp: clearance as "
                        "elastic rows, an anytime SQP under a CPU budget per re-plan; a "
                        "re-plan that cannot clear the forecast returns the plan that misses "
                        "the threshold least) or penalty (alias fatrop: the paper's penalty "
                        f"loop, alpha raised until the plan keeps the threshold); default "
                        f"{TRUE_ENERGY['replanner']}, penalty with --free-end (it keeps the "
                        "threshold "
                        "more often there: docs/realtime.md, 'harness.commands.plan')")
    add_anytime_options(p)
    p.add_argument("--realtime", action="store_true",
                   help="real CPU clocks, as on a robot: budgets and --deadline-ms count the "
                        "planning thread's CPU, a re-plan past its deadline is dropped (the arm "
                        "follows its last plan; deadline_misses in PLAN.json), the first "
                        "plan shares the cold budget, and the motion runs in real time (each "
                        "obstacle sample taken at its time: the command takes at least "
                        "--duration); default: nominal clocks, and the first plan solved to "
                        "convergence, by the other method if need be")
    p.add_argument("--bank", type=int, default=None, metavar="N",
                   help="anytime: keep a plan on each way round the obstacle (a bank of at "
                        "most N homotopy classes: which side each link passes it), every "
                        "class re-planned from the arm's state within the re-plan's shared "
                        "budget, the cheapest followed; the global search's plans join it. "
                        "PLAN.json's bank has each re-plan's classes and the switches "
                        f"(default {TRUE_ENERGY['bank'].size}; 1: one plan, re-planned)")
    p.add_argument("--bank-guidance", action="store_true",
                   help="anytime bank: hold each other class's re-plan in its class by linear "
                        "guidance (each near link's clearance row measured along the side it "
                        "passed on: de Groot et al.'s T-MPC); the plan followed stays free")
    p.add_argument("--global-search", action=argparse.BooleanOptionalAction,
                   default=None,
                   help="anytime: a global search beside the re-plans, solving the forecast "
                        "from many starts (the obstacle passed each side, above, below; random "
                        "starts) to convergence; a re-plan adopts its plan when, re-solved warm "
                        "within its budget, it spends less and keeps the clearance (nominal "
                        "clocks: offered a fixed number of obstacle samples later; --realtime: "
                        "in another process, when ready). PLAN.json's global_search counts "
                        "the adoptions (default: on)")
    p.add_argument("--replan-iterations", type=int, default=None,
                   help="real-time iterations: each re-plan first takes this many iterations "
                        "of CasADi's feasible SQP from the last plan and the arm follows the "
                        "iterate if it keeps the threshold and the limits, going on from it "
                        "at the next obstacle sample (0, the default: every re-plan solved "
                        "to convergence)")
    p.add_argument("--no-compile", action="store_true",
                   help="evaluate the NLP in CasADi's virtual machine instead of compiled C "
                        "(compiled once per problem with the system C compiler, cached)")
    end = p.add_mutually_exclusive_group()
    end.add_argument("--rest-at-goal", action="store_true",
                     help="require zero velocity at the goal (the default)")
    end.add_argument("--free-end", action="store_true",
                     help="leave the end velocity free (the paper's formulation): the optimum may "
                     "arrive moving, and its energy then leaves out the braking")
    p.add_argument("--no-replan", action="store_true", help="follow the first plan throughout")
    p.add_argument("--out", required=True, help="output PLAN.json")
    # Let "--goal -1.57,0.8,-1.0" through: argparse only takes "-1.5"-like strings as
    # values, and would read a comma-separated vector starting with a minus as an option.
    p._negative_number_matcher = re.compile(r"^-\.?\d")
    p.set_defaults(func=run)


def run(args) -> int:
    model_file = read_model(args.model)
    # once: --robot, else the model's
    arm = resolve_arm(args.robot, model=model_file.recorded, chain=chain_option(args))
    logger = logging.getLogger(compiled.__name__)
    notice = BuildNotice(arm.label)
    logger.addHandler(notice)
    logger.setLevel(logging.INFO)
    try:
        return _run(args, arm, model_file, notice)
    finally:
        logger.removeHandler(notice)


def parse(argv) -> argparse.Namespace:
    """`plan`'s options from its arguments (argv without the command's name)."""
    parser = argparse.ArgumentParser(prog="torquebench")
    register(parser.add_subparsers())
    return parser.parse_args(["plan", *argv])


class Planned(NamedTuple):
    """What `plan` executed: the configuration that planned it, its scenario, the torque
    model, the penalty loop's solver, the checked result (feasible or not)."""

    config: PlannerConfig
    scenario: Scenario
    model: TorqueModel
    planner: Planner
    result: PlanResult


def planned(args, arm: Arm, model_file, notice: BuildNotice | None = None) -> Planned:
    """What `plan args` executes, checked but not written, feasible or not. PlanningError
    where the scenario cannot be planned (an unreachable goal, a search that must fail)."""
    config = config_from_options(args, arm)
    scenario = scenario_from_options(args, arm, config)
    if notice is not None:
        notice.joints = config.geometry.dof
    model = torque_model(model_file, arm)  # checks its joints against the arm's
    planner = Planner(model, config)
    defaulted = args.obstacle_from is None and args.obstacle_to is None
    unreachable = (default_obstacle_diagnosis(config, scenario, arm, defaulted)  # before a
                   or velocity_diagnosis(config, scenario))  # search that must fail
    if unreachable:
        raise PlanningError(unreachable)
    note = default_obstacle_notice(arm, defaulted)  # before the search: a failure has it too
    if note:
        print(note, file=sys.stderr)
    config, result = executed(model, config, scenario, planner, replan=not args.no_replan,
                              realtime=args.realtime, either=_either(args))
    return Planned(config, scenario, model, planner, result)


def _either(args) -> bool:
    """Whether `plan` tries both methods (neither asked for by name, nor real time)."""
    return not args.realtime and (args.replanner is None or args.no_replan)


def _run(args, arm: Arm, model_file, notice: BuildNotice) -> int:
    config, scenario, model, planner, result = planned(args, arm, model_file, notice)
    notice.finish()
    fallback_note(planner.config.replanner, config.replanner, args.no_replan)
    search_failure_note(result.execution.search_failures)
    first_plan_note(result.execution.first_plan_fallback)
    if not result.feasible:  # the torque limits' diagnosis builds IPOPT's NLP: only now
        raise PlanningError((torque_diagnosis(planner, scenario)
                             or infeasible(result.problems, config, scenario, _either(args)))
                            + notice.compiled_note())
    write_json(args.out, {**to_json(result, scenario, config, args.model),  # links whose
                          "unread_geometry": [u._asdict() for u in arm.unread_geometry]})  # mesh failed
    if args.trajectory:
        write_trajectory(args.trajectory, control_trajectory(
            result.execution, model, scenario.duration, args.rate or DEFAULT_RATE))
    print(f"wrote {args.out}: energy {result.energy:.4f} J, min clearance "
          f"{result.sample_clearance.min():.4f} m (closest: "
          f"{closest_link(result, config)['closest_link']}), "
          f"{len(result.execution.segments) - 1} re-plans{notice.compiled_note()}")
    return 0
