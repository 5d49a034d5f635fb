"""`torquebench plan`: an energy-optimal, obstacle-avoiding trajectory (paper III.G).

Defaults are the paper's scenario. The plan is written only if it is feasible
(solver converged, goal reached, limits kept, clearance held); otherwise the
command names the problem and exits 2 without writing.
"""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np

from harness.errors import UserError
from harness.io import write_json
from harness.robots.registry import DEFAULT_ROBOT, load_mujoco
from harness.robots.torque_models import load_torque_model
from planning.backends import SOLVERS
from planning.config import PlannerConfig, Scenario
from planning.errors import PlanningError
from planning.obstacle import LinearObstacle, SwayingObstacle
from planning.quadrature import RULES
from planning.replanning import execute
from planning.result import evaluate, to_json
from planning.solver import Planner

DEFAULT = Scenario()


def _vector(text: str, name: str, length: int = 3) -> tuple[float, ...]:
    try:
        values = tuple(float(x) for x in text.split(","))
    except ValueError:
        raise UserError(f"--{name} must be {length} comma-separated numbers, got '{text}'") from None
    if len(values) != length or not all(math.isfinite(v) for v in values):
        raise UserError(f"--{name} must be {length} finite comma-separated numbers, got '{text}'")
    return values


def _csv(values) -> str:
    return ",".join(repr(float(v)) for v in values)


def register(sub) -> None:
    p = sub.add_parser("plan", help="energy-optimal trajectory avoiding a moving obstacle")
    p.add_argument("--model", required=True, help="MODEL.json or 'pinocchio'")
    p.add_argument("--robot", default=DEFAULT_ROBOT, help="robot for the pinocchio baseline")
    p.add_argument("--start", default=_csv(DEFAULT.start), help="start angles q1,q2,q3 (rad)")
    p.add_argument("--goal", default=_csv(DEFAULT.goal), help="goal angles q1,q2,q3 (rad)")
    p.add_argument("--duration", type=float, default=DEFAULT.duration, help="motion time (s)")
    p.add_argument("--obstacle-from", default=_csv(DEFAULT.obstacle.start),
                   help="obstacle centre at t = 0 (m)")
    p.add_argument("--obstacle-to", default=_csv(DEFAULT.obstacle.end),
                   help="obstacle centre at t = duration (m)")
    p.add_argument("--samples", type=int, default=DEFAULT.obstacle.samples,
                   help="obstacle samples K over the motion")
    p.add_argument("--threshold", type=float, default=PlannerConfig.threshold,
                   help="clearance threshold lambda (m)")
    p.add_argument("--penalty", type=float, default=PlannerConfig.penalty_weight,
                   help="penalty weight alpha (J/m^2 per obstacle sample)")
    p.add_argument("--energy-samples", type=int, default=PlannerConfig.energy_samples,
                   help="power samples N of the energy objective")
    p.add_argument("--energy-quadrature", choices=RULES, default=PlannerConfig.energy_quadrature,
                   help="where the power is sampled: paper (eq. 18, s_i = i/N), gauss "
                        "(Gauss-Legendre, plans with the true energy at N ~ 20), simpson")
    p.add_argument("--degree", type=int, default=PlannerConfig.degree,
                   help="degree of the joint polynomials (paper: 4; 4..9)")
    p.add_argument("--power-smoothing", type=float, default=PlannerConfig.power_smoothing,
                   help="W; 0: exact |P| (epigraph), > 0: sqrt(P^2 + eps^2) - eps")
    p.add_argument("--obstacle-sway", default="0,0,0",
                   help="sway amplitude vector (m) added to the linear obstacle path as "
                        "sway sin(2 pi periods t / duration)")
    p.add_argument("--sway-periods", type=float, default=1.0, help="sway periods over the motion")
    p.add_argument("--torque-limit", default=None,
                   help="per-joint torque limits t1,t2,t3 (N m), or 'none'; default: the "
                        "robot MJCF's motor ctrlrange times gear")
    p.add_argument("--solver", choices=SOLVERS, default=PlannerConfig.solver,
                   help="NLP solver (CasADi plugin); ipopt is the paper's")
    p.add_argument("--starts", type=int, default=PlannerConfig.starts,
                   help="start points of the cold plan (the best is kept)")
    p.add_argument("--deadline-ms", type=float, default=0.0,
                   help="CPU ms a re-plan may take; a later one is dropped and the last plan "
                        "kept, as on a real-time controller (0, the default: no deadline; "
                        "the obstacle's sample period is 10 ms)")
    p.add_argument("--no-compile", action="store_true",
                   help="evaluate the NLP in CasADi's virtual machine instead of compiled C "
                        "(compiled once per problem with the system C compiler, cached)")
    p.add_argument("--rest-at-goal", action="store_true", help="also require zero end velocity")
    p.add_argument("--no-replan", action="store_true", help="follow the first plan throughout")
    p.add_argument("--out", required=True, help="output PLAN.json")
    # Let "--goal -1.57,0.8,-1.0" through: argparse only takes "-1.5"-like strings as
    # values, and would read a comma-separated vector starting with a minus as an option.
    p._negative_number_matcher = re.compile(r"^-\.?\d")
    p.set_defaults(func=run)


def plant_torque_limit(robot: str) -> tuple[float, ...] | None:
    """|tau_i| bound (N m) of each joint from the robot's MJCF motors (ctrlrange x gear), in
    joint order; None if a motor is unlimited or the motors do not map 1:1 to joints."""
    model = load_mujoco(robot)
    joints = model.actuator_trnid[:, 0]
    if model.nu != model.njnt or sorted(joints) != list(range(model.njnt)) \
            or not all(model.actuator_ctrllimited):
        return None
    reach = np.abs(model.actuator_ctrlrange).min(axis=1) * np.abs(model.actuator_gear[:, 0])
    limit = np.empty(model.njnt)
    limit[joints] = reach
    return tuple(float(v) for v in limit)


def _torque_limit(args) -> tuple[float, ...] | None:
    if args.torque_limit is None:
        return plant_torque_limit(args.robot)
    if args.torque_limit.strip().lower() == "none":
        return None
    limit = _vector(args.torque_limit, "torque-limit")
    if not all(v > 0 for v in limit):
        raise UserError(f"--torque-limit must be positive, got '{args.torque_limit}'")
    return limit


def _setup(args) -> tuple[PlannerConfig, Scenario]:
    if not args.duration > 0 or not math.isfinite(args.duration):
        raise PlanningError(f"--duration must be > 0 s, got {args.duration}")
    if not (args.threshold > 0 and args.penalty >= 0) or args.samples < 2 \
            or args.energy_samples < 1:
        raise UserError("--threshold must be > 0, --penalty >= 0, --samples >= 2, "
                        "--energy-samples >= 1")
    if args.starts < 1 or not (math.isfinite(args.deadline_ms) and args.deadline_ms >= 0):
        raise UserError("--starts must be >= 1 and --deadline-ms a finite number >= 0")
    if not 4 <= args.degree <= 9:
        raise UserError(f"--degree must be in 4..9, got {args.degree}")
    if args.energy_quadrature == "simpson" and (args.energy_samples < 3
                                                 or args.energy_samples % 2 == 0):
        raise UserError("--energy-quadrature simpson needs an odd --energy-samples >= 3")
    if not (math.isfinite(args.power_smoothing) and args.power_smoothing >= 0
            and math.isfinite(args.sway_periods)):
        raise UserError("--power-smoothing must be >= 0 and --sway-periods finite")
    config = dataclasses.replace(PlannerConfig(), threshold=args.threshold,
                                 penalty_weight=args.penalty, rest_at_goal=args.rest_at_goal,
                                 energy_samples=args.energy_samples,
                                 energy_quadrature=args.energy_quadrature, degree=args.degree,
                                 power_smoothing=args.power_smoothing,
                                 torque_limit=_torque_limit(args), solver=args.solver,
                                 starts=args.starts, compile_code=not args.no_compile,
                                 replan_deadline_ms=args.deadline_ms or None)
    path = (_vector(args.obstacle_from, "obstacle-from"),
            _vector(args.obstacle_to, "obstacle-to"), args.duration, args.samples)
    sway = _vector(args.obstacle_sway, "obstacle-sway")
    obstacle = (SwayingObstacle(*path, sway=sway, periods=args.sway_periods) if any(sway)
                else LinearObstacle(*path))
    scenario = Scenario(_vector(args.start, "start"), _vector(args.goal, "goal"),
                        args.duration, obstacle)
    scenario.validate(config)
    return config, scenario


def run(args) -> int:
    config, scenario = _setup(args)
    model = load_torque_model(args.model, args.robot)
    if model.dof != 3:
        raise UserError(f"the planner drives the 3-joint arm; model has {model.dof} joints")
    planner = Planner(model, config)
    result = evaluate(execute(planner, scenario, replan=not args.no_replan), scenario, model,
                      config)
    if not result.feasible:
        raise PlanningError("no feasible plan: " + "; ".join(result.problems))
    write_json(args.out, to_json(result, scenario, config, args.model))
    print(f"wrote {args.out}: energy {result.energy:.4f} J, min clearance "
          f"{result.sample_clearance.min():.4f} m, {len(result.execution.segments) - 1} re-plans")
    return 0
