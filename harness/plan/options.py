"""What `torquebench plan` plans: the arm's planner configuration (harness.plan.arm_config.
planner_config) with the options the user gave changed, and only those (an option left out
is None), and the scenario of its motion options. Checked here, each option once."""

from __future__ import annotations

import dataclasses
import math

from harness.errors import UserError
from harness.plan.anytime_options import anytime_options
from harness.plan.arm_config import DURATION, default_obstacle, planner_config
from harness.plan.limits import link_geometry, rate_limits, torque_limit, vector
from harness.robots.arm import Arm
from planning.config import PlannerConfig, Scenario
from planning.errors import PlanningError
from planning.formulation.obstacle import LinearObstacle, SwayingObstacle
from planning.formulation.quadrature import splits_evenly

# the power samples N each rule plans with when --energy-samples is left out (split: 3 per
# interval); true_energy_config's N = 20 with its Gauss rule
SAMPLES = {"paper": 10, "gauss": 20, "simpson": 21}
# options -> PlannerConfig fields they set as given
FIELDS = {"threshold": "threshold", "penalty": "penalty_weight", "degree": "degree",
          "energy_quadrature": "energy_quadrature", "power_breaks": "power_breaks",
          "power_smoothing": "power_smoothing", "starts": "starts"}
PENALTY = {"solver": "solver", "polish": "polish", "polish_samples": "polish_samples"}


def given(args, names: dict) -> dict:
    """{field: value} of the options in `names` ({option: field}) the user gave."""
    return {field: getattr(args, option) for option, field in names.items()
            if getattr(args, option) is not None}


def config_from_options(args, arm: Arm) -> PlannerConfig:
    """The configuration `plan` plans with on arm: planner_config(arm) with the given
    options, the arm's velocity limits, capsules and compiled code (quick to build unless a
    CPU clock decides the plan) unless the options say otherwise."""
    _check_ranges(args)
    base = planner_config(arm)
    dof = base.geometry.dof
    fields = given(args, FIELDS)
    quadrature = fields.get("energy_quadrature", base.energy_quadrature)
    if args.energy_samples is not None:
        fields["energy_samples"] = args.energy_samples
    elif "energy_quadrature" in fields or "power_breaks" in fields:
        fields["energy_samples"] = SAMPLES[quadrature] if quadrature != "split" else \
            3 * (max(fields.get("power_breaks", base.power_breaks), 0) + 1)
    if args.free_end:
        fields["rest_at_goal"] = False
    replanner = args.replanner or ("penalty" if args.free_end else None)
    if replanner is not None:
        fields["replanner"] = replanner
    if args.deadline_ms:
        fields["replan_deadline_ms"] = args.deadline_ms
    if args.settle_horizon is not None:
        fields["settle_horizon"] = args.settle_horizon
    penalty = given(args, PENALTY)
    if args.replan_iterations:
        penalty["replan_iterations"] = args.replan_iterations
    search = {} if args.global_search is None else {"enabled": args.global_search}
    if args.bank is not None and args.bank < 1:
        raise UserError(f"--bank must be a whole number >= 1, got {args.bank}")
    bank = ({} if args.bank is None else {"size": args.bank}) | \
        ({"guided": True} if args.bank_guidance else {})
    config = dataclasses.replace(
        base, **fields, geometry=link_geometry(args, arm, base.geometry),
        torque_limit=torque_limit(args, arm, dof), **rate_limits(args, arm, dof),
        compile_code=not args.no_compile,
        quick_build=not (args.realtime or args.deadline_ms),  # -O0 first where no CPU decides
        penalty=dataclasses.replace(base.penalty, **penalty),
        anytime=dataclasses.replace(base.anytime, **anytime_options(args)),
        global_search=dataclasses.replace(base.global_search, **search),
        bank=dataclasses.replace(base.bank, **bank))
    _check_together(config)
    return config


def _check_ranges(args) -> None:
    """Each given option within its range (the defaults are)."""
    def bad(name: str, test) -> bool:
        value = getattr(args, name)
        return value is not None and not test(value)

    if bad("duration", lambda v: v > 0 and math.isfinite(v)):
        raise PlanningError(f"--duration must be > 0 s, got {args.duration}")
    if bad("threshold", lambda v: v > 0) or bad("penalty", lambda v: v >= 0) \
            or bad("samples", lambda v: v >= 2) or bad("energy_samples", lambda v: v >= 1):
        raise UserError("--threshold must be > 0, --penalty >= 0, --samples >= 2, "
                        "--energy-samples >= 1")
    if bad("starts", lambda v: v >= 1) or bad("deadline_ms", lambda v: math.isfinite(v) and v >= 0):
        raise UserError("--starts must be >= 1 and --deadline-ms a finite number >= 0")
    if bad("replan_iterations", lambda v: v >= 0):
        raise UserError(f"--replan-iterations must be >= 0, got {args.replan_iterations}")
    if bad("polish", lambda v: v >= 0):
        raise UserError("--polish must be >= 0; with it, --power-breaks >= 1 and "
                        "--polish-samples a positive multiple of --power-breaks + 1")
    if bad("degree", lambda v: 4 <= v <= 9):
        raise UserError(f"--degree must be in 4..9, got {args.degree}")
    if bad("power_smoothing", lambda v: math.isfinite(v) and v >= 0) \
            or bad("sway_periods", math.isfinite):
        raise UserError("--power-smoothing must be >= 0 and --sway-periods finite")
    if bad("rate", lambda v: math.isfinite(v) and v > 0):
        raise UserError(f"--rate must be a finite number > 0 Hz, got {args.rate}")
    if args.rate is not None and args.trajectory is None:
        raise UserError("--rate needs --trajectory (the CSV it samples)")


def _check_together(config: PlannerConfig) -> None:
    """The options that must agree with each other, as the configuration has them."""
    if config.penalty.polish and not splits_evenly(config.penalty.polish_samples,
                                                   config.power_breaks):
        raise UserError("--polish must be >= 0; with it, --power-breaks >= 1 and "
                        "--polish-samples a positive multiple of --power-breaks + 1")
    rule, samples = config.energy_quadrature, config.energy_samples
    if rule == "simpson" and (samples < 3 or samples % 2 == 0):
        raise UserError("--energy-quadrature simpson needs an odd --energy-samples >= 3")
    if rule == "split" and not splits_evenly(samples, config.power_breaks):
        raise UserError("--energy-quadrature split needs --power-breaks >= 1 and "
                        "--energy-samples a multiple of --power-breaks + 1")


def scenario_from_options(args, arm: Arm, config: PlannerConfig) -> Scenario:
    """The motion the options ask for: --start and --goal, else the arm's registered motion;
    past the obstacle path of --obstacle-from/--obstacle-to, each left out the default
    path's (harness.plan.arm_config.default_obstacle), swaying by --obstacle-sway; checked
    against the configuration's limits."""
    duration = DURATION if args.duration is None else args.duration
    dof = config.geometry.dof
    default = default_obstacle(duration, args.samples, arm)
    path = (default.start if args.obstacle_from is None else vector(args.obstacle_from, "obstacle-from"),
            default.end if args.obstacle_to is None else vector(args.obstacle_to, "obstacle-to"),
            duration, default.samples)
    sway = (0.0,) * 3 if args.obstacle_sway is None else vector(args.obstacle_sway, "obstacle-sway")
    periods = 1.0 if args.sway_periods is None else args.sway_periods
    obstacle = (SwayingObstacle(*path, sway=sway, periods=periods) if any(sway)
                else LinearObstacle(*path))
    missing = [f"--{n}" for n in ("start", "goal") if getattr(args, n) is None]
    if missing and arm.entry.motion is None:  # every missing option named at once
        raise UserError(f"{' and '.join(missing)} {'are' if len(missing) > 1 else 'is'} needed "
                        f"on robot {arm.label} (it registers no motion): {dof} comma-separated "
                        "joint angles (rad) each")
    scenario = Scenario(_angles(args, arm, "start", dof), _angles(args, arm, "goal", dof),
                        duration, obstacle, (0.0,) * dof)
    scenario.validate(config)
    return scenario


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
