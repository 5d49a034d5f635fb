"""The anytime SQP's options of `torquebench plan` (planning.config.AnytimeOptions)."""

from __future__ import annotations

import math

from harness.errors import UserError
from planning.config import PlannerConfig


def add_anytime_options(p, default: PlannerConfig) -> None:
    p.add_argument("--replan-budget-ms", type=float, default=default.anytime.replan_budget_ms,
                   help="anytime: ms a re-plan may take (it returns its best iterate then): "
                        "counted in SQP iterations of a fixed nominal cost per robot (the same "
                        "plan on any machine and load; PLAN.json reports the real CPU beside), "
                        "or CPU ms with --realtime")
    p.add_argument("--warm-radius", type=float, default=default.anytime.warm_radius,
                   help="anytime: the trust region's first radius in a re-plan (a box on the "
                        "trajectory's polynomial coefficients, rad); smaller keeps a re-plan "
                        "nearer the plan it starts from (docs/realtime.md, 'Warm radius'; "
                        f"default {default.anytime.warm_radius:g})")
    p.add_argument("--settle-horizon", type=float, default=default.settle_horizon,
                   help="s before the end within which an unconverged re-plan is followed as "
                        "it is instead of gone on from at every sample (a plan that dips below "
                        "the threshold is still re-planned): a re-plan that short can only make "
                        "the stop harder (docs/realtime.md, 'The last re-plans'; default "
                        f"{default.settle_horizon:g})")


def anytime_options(args) -> dict:
    """The AnytimeOptions fields the options set (PlannerConfig.with_anytime's keywords)."""
    for name, value in (("--replan-budget-ms", args.replan_budget_ms),
                        ("--warm-radius", args.warm_radius)):
        if not (math.isfinite(value) and value > 0):
            raise UserError(f"{name} must be a finite number > 0, got {value}")
    return {"replan_budget_ms": args.replan_budget_ms, "warm_radius": args.warm_radius}


def settle_horizon(args) -> float:
    """--settle-horizon (s), checked."""
    if not (math.isfinite(args.settle_horizon) and args.settle_horizon >= 0):
        raise UserError(f"--settle-horizon must be a finite number >= 0, got "
                        f"{args.settle_horizon}")
    return args.settle_horizon
