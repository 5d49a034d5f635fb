"""`torquebench plan`: an energy-optimal, obstacle-avoiding trajectory (paper III.G).

Defaults are the paper's scenario. The plan is written only if it is feasible
(solver converged, goal reached, limits kept, clearance held); otherwise the
command names the problem and exits 2 without writing.
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import math
import re
import sys

from harness.errors import UserError
from harness.io import write_json
from harness.plan.anytime_options import add_anytime_options, anytime_options, settle_horizon
from harness.plan.arm_config import planner_config
from harness.plan.limits import link_geometry, rate_limits, torque_limit, vector, vector_text
from harness.plan.messages import (
    BuildNotice,
    default_obstacle_diagnosis,
    default_obstacle_notice,
    fallback_note,
    infeasible,
    torque_diagnosis,
    velocity_diagnosis,
)
from harness.plan.trajectory_csv import DEFAULT_RATE, write_trajectory
from harness.robots.resolve import Arm, resolve_arm
from harness.robots.torque_models import read_model, torque_model
from planning.config import ALIASES, REPLANNERS, PlannerConfig, Scenario, true_energy_config
from planning.control import control_trajectory
from planning.errors import PlanningError
from planning.formulation import compiled
from planning.formulation.obstacle import LinearObstacle, SwayingObstacle
from planning.formulation.quadrature import RULES, splits_evenly
from planning.penalty.backends import SOLVERS
from planning.penalty.solver import Planner
from planning.planners import executed
from planning.result import closest_link, to_json

DEFAULT = Scenario()
PLANNER = true_energy_config()
SAMPLES = {"paper": 10, "gauss": PLANNER.energy_samples, "simpson": 21}  # split: 3 per interval


def register(sub) -> None:
    p = sub.add_parser("plan", help="energy-optimal trajectory avoiding a moving obstacle")
    p.add_argument("--model", required=True, help="MODEL.json or 'pinocchio'")
    p.add_argument("--robot", default=None,
                   help="registered robot or URDF/MJCF path: its links, joint and torque limits and its "
                        "pinocchio baseline (default: the model's robot, else lynxmotion)")
    p.add_argument("--start", default=None,
                   help="start angles, one per joint (rad); default: the robot's registered "
                        "motion (on the Lynxmotion the paper's, " + vector_text(DEFAULT.start) + ")")
    p.add_argument("--goal", default=None,
                   help="goal angles, one per joint (rad); default: the robot's registered "
                        "motion (on the Lynxmotion the paper's, " + vector_text(DEFAULT.goal) + ")")
    p.add_argument("--duration", type=float, default=DEFAULT.duration, help="motion time (s)")
    p.add_argument("--obstacle-from", default=None,
                   help="obstacle centre at t = 0 (m); default: the Lynxmotion paper scenario's, "
                        + vector_text(DEFAULT.obstacle.start))
    p.add_argument("--obstacle-to", default=None,
                   help="obstacle centre at t = duration (m); default: the Lynxmotion paper "
                        "scenario's, " + vector_text(DEFAULT.obstacle.end))
    p.add_argument("--samples", type=int, default=DEFAULT.obstacle.samples,
                   help="obstacle samples K over the motion")
    p.add_argument("--threshold", type=float, default=PlannerConfig.threshold,
                   help="clearance threshold lambda (m)")
    p.add_argument("--penalty", type=float, default=PlannerConfig.penalty_weight,
                   help="penalty weight alpha (J/m^2 per obstacle sample)")
    p.add_argument("--energy-samples", type=int, default=None,
                   help="power samples N of the energy objective (default: 20 for gauss, the "
                        "paper's 10 for paper, 21 for simpson, 3 per interval for split)")
    p.add_argument("--energy-quadrature", choices=RULES, default=PLANNER.energy_quadrature,
                   help="where the power is sampled: gauss (Gauss-Legendre, the default: plans "
                        "with the true energy at N = 20), paper (eq. 18, s_i = i/N), simpson, "
                        "split (Gauss between the power's sign changes)")
    p.add_argument("--power-breaks", type=int, default=PlannerConfig.power_breaks,
                   help="split: breaks between the quadrature's intervals, put where the "
                        "power changes sign; --energy-samples must be a multiple of this + 1")
    p.add_argument("--degree", type=int, default=PlannerConfig.degree,
                   help="degree of the joint polynomials (paper: 4; 4..9)")
    p.add_argument("--power-smoothing", type=float, default=PlannerConfig.power_smoothing,
                   help="W; 0: exact |P| (epigraph), > 0: sqrt(P^2 + eps^2) - eps")
    p.add_argument("--obstacle-sway", default="0,0,0",
                   help="sway amplitude vector (m) added to the linear obstacle path as "
                        "sway sin(2 pi periods t / duration)")
    p.add_argument("--sway-periods", type=float, default=1.0, help="sway periods over the motion")
    p.add_argument("--torque-limit", default=None,
                   help="per-joint torque limits (N m, one per joint), or 'none'; default: the "
                        "robot MJCF's motor ctrlrange times gear, else the URDF effort limits")
    p.add_argument("--velocity-limit", default=None,
                   help="per-joint velocity limits (rad/s, one per joint), or 'none'; default: "
                        "the URDF's <limit velocity>")
    p.add_argument("--accel-limit", default=None,
                   help="acceleration limit (rad/s^2): one for every joint or one per joint "
                        "(default: none)")
    p.add_argument("--link-radius", default="collision",
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
    p.add_argument("--starts", type=int, default=PLANNER.starts,
                   help="start points of the cold plan (the best is kept)")
    p.add_argument("--polish", type=int, default=PLANNER.penalty.polish,
                   help="the best N distinct cold plans are solved again with the split "
                        "quadrature (breaks at the power's sign changes) and the one that "
                        "spends least kept (0: none)")
    p.add_argument("--polish-samples", type=int, default=PLANNER.penalty.polish_samples,
                   help="nodes of the polishing quadrature: a multiple of --power-breaks + 1")
    p.add_argument("--deadline-ms", type=float, default=0.0,
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
                        f"{PLANNER.replanner}, penalty with --free-end (it keeps the threshold "
                        "more often there: docs/realtime.md, 'harness.commands.plan')")
    add_anytime_options(p, PLANNER)
    p.add_argument("--realtime", action="store_true",
                   help="real CPU clocks, as on a robot: budgets and --deadline-ms count the "
                        "planning thread's CPU, a re-plan past its deadline is dropped (the arm "
                        "follows its last plan; deadline_misses in PLAN.json) and the first "
                        "plan shares the cold budget; default: nominal clocks, and the first "
                        "plan solved to convergence, by the other method if need be")
    p.add_argument("--global-search", action=argparse.BooleanOptionalAction,
                   default=PLANNER.global_search.enabled,
                   help="anytime: a global search beside the re-plans, solving the forecast "
                        "from many starts (the obstacle passed each side, above, below; random "
                        "starts) to convergence; a re-plan adopts its plan when, re-solved warm "
                        "within its budget, it spends less and keeps the clearance (nominal "
                        "clocks: offered a fixed number of obstacle samples later; --realtime: "
                        "in another process, when ready). PLAN.json's global_search counts "
                        f"the adoptions (default: {'on' if PLANNER.global_search.enabled else 'off'})")
    p.add_argument("--replan-iterations", type=int, default=0,
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


def _angles(args, arm: Arm, name: str, dof: int) -> tuple[float, ...]:
    """--start or --goal, else the arm's registered motion (the Lynxmotion's: the paper's)."""
    text = getattr(args, name)
    if text is None:
        motion = arm.entry.motion
        if motion is None:
            raise UserError(f"--{name} is needed on robot {arm.label}: {dof} comma-separated "
                            "joint angles (rad)")
        return tuple(motion[0 if name == "start" else 1])
    return vector(text, name, dof)


def _setup(args, arm: Arm) -> tuple[PlannerConfig, Scenario]:
    if args.energy_samples is None:
        args.energy_samples = SAMPLES[args.energy_quadrature] \
            if args.energy_quadrature != "split" else 3 * (max(args.power_breaks, 0) + 1)
    if not args.duration > 0 or not math.isfinite(args.duration):
        raise PlanningError(f"--duration must be > 0 s, got {args.duration}")
    if not (args.threshold > 0 and args.penalty >= 0) or args.samples < 2 \
            or args.energy_samples < 1:
        raise UserError("--threshold must be > 0, --penalty >= 0, --samples >= 2, "
                        "--energy-samples >= 1")
    if args.starts < 1 or not (math.isfinite(args.deadline_ms) and args.deadline_ms >= 0):
        raise UserError("--starts must be >= 1 and --deadline-ms a finite number >= 0")
    if args.replan_iterations < 0:
        raise UserError(f"--replan-iterations must be >= 0, got {args.replan_iterations}")
    if args.polish < 0 or (args.polish and not splits_evenly(args.polish_samples, args.power_breaks)):
        raise UserError("--polish must be >= 0; with it, --power-breaks >= 1 and "
                        "--polish-samples a positive multiple of --power-breaks + 1")
    if not 4 <= args.degree <= 9:
        raise UserError(f"--degree must be in 4..9, got {args.degree}")
    if args.energy_quadrature == "simpson" and (args.energy_samples < 3
                                                 or args.energy_samples % 2 == 0):
        raise UserError("--energy-quadrature simpson needs an odd --energy-samples >= 3")
    if args.energy_quadrature == "split" and not splits_evenly(args.energy_samples, args.power_breaks):
        raise UserError("--energy-quadrature split needs --power-breaks >= 1 and "
                        "--energy-samples a multiple of --power-breaks + 1")
    if not (math.isfinite(args.power_smoothing) and args.power_smoothing >= 0
            and math.isfinite(args.sway_periods)):
        raise UserError("--power-smoothing must be >= 0 and --sway-periods finite")
    config = dataclasses.replace(planner_config(arm), threshold=args.threshold,
                                 penalty_weight=args.penalty, rest_at_goal=not args.free_end,
                                 energy_samples=args.energy_samples,
                                 energy_quadrature=args.energy_quadrature, degree=args.degree,
                                 power_smoothing=args.power_smoothing,
                                 power_breaks=args.power_breaks,
                                 torque_limit=None)
    dof = config.geometry.dof
    config = dataclasses.replace(config, geometry=link_geometry(args, arm, config.geometry))
    config = dataclasses.replace(config, torque_limit=torque_limit(args, arm, dof),
                                 **rate_limits(args, arm, dof))
    if args.rate is not None and not (math.isfinite(args.rate) and args.rate > 0):
        raise UserError(f"--rate must be a finite number > 0 Hz, got {args.rate}")
    if args.rate is not None and args.trajectory is None:
        raise UserError("--rate needs --trajectory (the CSV it samples)")
    config = config.with_penalty(solver=args.solver or config.penalty.solver,
                                 polish=args.polish, polish_samples=args.polish_samples,
                                 replan_iterations=args.replan_iterations or None)
    config = config.with_global_search(enabled=args.global_search)
    config = dataclasses.replace(config.with_anytime(**anytime_options(args)),
                                 starts=args.starts, compile_code=not args.no_compile,
                                 # -O0 first where no CPU time decides the plan
                                 quick_build=not (args.realtime or args.deadline_ms),
                                 replan_deadline_ms=args.deadline_ms or None,
                                 settle_horizon=settle_horizon(args),
                                 replanner=args.replanner or ("penalty" if args.free_end
                                                              else PLANNER.replanner))
    default = DEFAULT.obstacle  # neither option given: the Lynxmotion paper scenario's path
    path = (default.start if args.obstacle_from is None else vector(args.obstacle_from, "obstacle-from"),
            default.end if args.obstacle_to is None else vector(args.obstacle_to, "obstacle-to"),
            args.duration, args.samples)
    sway = vector(args.obstacle_sway, "obstacle-sway")
    obstacle = (SwayingObstacle(*path, sway=sway, periods=args.sway_periods) if any(sway)
                else LinearObstacle(*path))
    scenario = Scenario(_angles(args, arm, "start", dof), _angles(args, arm, "goal", dof),
                        args.duration, obstacle, (0.0,) * dof)
    scenario.validate(config)
    return config, scenario


def run(args) -> int:
    model_file = read_model(args.model)
    arm = resolve_arm(args.robot, model=model_file.recorded)  # once: --robot, else the model's
    logger = logging.getLogger(compiled.__name__)
    notice = BuildNotice(arm.label)
    logger.addHandler(notice)
    logger.setLevel(logging.INFO)
    try:
        return _run(args, arm, model_file, notice)
    finally:
        logger.removeHandler(notice)


def _run(args, arm: Arm, model_file, notice: BuildNotice) -> int:
    config, scenario = _setup(args, arm)
    notice.joints = config.geometry.dof
    model = torque_model(model_file, arm)  # checks its joints against the arm's
    planner = Planner(model, config)
    defaulted = args.obstacle_from is None and args.obstacle_to is None
    unreachable = (default_obstacle_diagnosis(config, scenario, arm, defaulted)  # before a
                   or velocity_diagnosis(config, scenario))  # search that must fail
    if unreachable:
        raise PlanningError(unreachable)
    either = not args.realtime and (args.replanner is None or args.no_replan)  # both methods
    config, result = executed(model, config, scenario, planner, replan=not args.no_replan,
                              realtime=args.realtime, either=either)
    notice.finish()
    fallback_note(planner.config.replanner, config.replanner, args.no_replan)
    if not result.feasible:  # the torque limits' diagnosis builds IPOPT's NLP: only now
        raise PlanningError(torque_diagnosis(planner, scenario)
                            or infeasible(result.problems, config, scenario, either))
    write_json(args.out, to_json(result, scenario, config, args.model))
    if args.trajectory:
        write_trajectory(args.trajectory, control_trajectory(
            result.execution, model, scenario.duration, args.rate or DEFAULT_RATE))
    print(f"wrote {args.out}: energy {result.energy:.4f} J, min clearance "
          f"{result.sample_clearance.min():.4f} m (closest: "
          f"{closest_link(result, config)['closest_link']}), "
          f"{len(result.execution.segments) - 1} re-plans")
    notice = default_obstacle_notice(arm, defaulted)
    if notice:
        print(notice, file=sys.stderr)
    return 0
