"""The anytime SQP's options of `torquebench plan` (planning.config.AnytimeOptions)."""

from __future__ import annotations

import math

from harness.errors import UserError
from planning.config import AnytimeOptions, PlannerConfig


def add_anytime_options(p) -> None:
    """The anytime SQP's options, each None when left out (AnytimeOptions' default then)."""
    default = AnytimeOptions()
    p.add_argument("--replan-budget-ms", type=float, default=None,
                   help="anytime: ms a re-plan may take (it returns its best iterate then): "
                        "counted in SQP iterations of a fixed nominal cost per robot (the same "
                        "plan on any machine and load; PLAN.json reports the real CPU beside), "
                        f"or CPU ms with --realtime (default {default.replan_budget_ms:g})")
    p.add_argument("--warm-radius", type=float, default=None,
                   help="anytime: the trust region's first radius in a re-plan (a box on the "
                        "trajectory's polynomial coefficients, rad); smaller keeps a re-plan "
                        "nearer the plan it starts from (docs/realtime.md, 'Warm radius'; "
                        f"default {default.warm_radius:g})")
    p.add_argument("--settle-horizon", type=float, default=None,
                   help="s before the end within which an unconverged re-plan is followed as "
                        "it is instead of gone on from at every sample (a plan that dips below "
                        "the threshold is still re-planned): a re-plan that short can only make "
                        "the stop harder (docs/realtime.md, 'The last re-plans'; default "
                        f"{PlannerConfig.settle_horizon:g})")


def anytime_options(args) -> dict:
    """The AnytimeOptions fields the given options set, checked; and --settle-horizon, checked
    (a PlannerConfig field: harness.plan.options sets it)."""
    changes = {}
    for name, field, value in (("--replan-budget-ms", "replan_budget_ms", args.replan_budget_ms),
                               ("--warm-radius", "warm_radius", args.warm_radius)):
        if value is None:
            continue
        if not (math.isfinite(value) and value > 0):
            raise UserError(f"{name} must be a finite number > 0, got {value}")
        changes[field] = value
    horizon = args.settle_horizon
    if horizon is not None and not (math.isfinite(horizon) and horizon >= 0):
        raise UserError(f"--settle-horizon must be a finite number >= 0, got {horizon}")
    return changes
