"""Planning on any robot, robot in, results out: what an executed plan costs against the
physical bound, and the checks every plan must pass (shared by the planning section and the
robot extras that plan)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from harness.report.results import Check, Target, check
from harness.robots.baseline import PinocchioModel
from planning.result import CLEARANCE_TOLERANCE, END_TOLERANCE, closest_link, executed_energy

# the bench's executed plans count each iteration of the anytime SQP as this many ms of its
# budgets (AnytimeOptions.iteration_ms): the same plans on a loaded machine, their real CPU
# reported beside against the budget (the cost it stands for: docs/realtime.md, 'Nominal clock')
REPLAY_ITERATION_MS = 0.5
REST_TOLERANCE = 1e-6  # rad/s at the goal
ENERGY_TOLERANCE = 1e-3  # J below the physical bound still counted (quadrature)


def reproducible(config):
    """config with its anytime budgets counted in SQP iterations (REPLAY_ITERATION_MS each)."""
    return config.with_anytime(iteration_ms=REPLAY_ITERATION_MS)


def energy_bound(model: pin.Model, result) -> float:
    """What any motion from rest to rest along result's path must spend (J): |V(T) - V(0)
    + dissipated|, the work the motors do net of the viscous damping's, since the kinetic
    energy is zero at both ends and integral |P| >= |integral P|."""
    data = model.createData()
    v = [pin.computePotentialEnergy(model, data, result.q[k]) for k in (0, -1)]
    damping = np.asarray(model.damping)
    p = np.sum(damping * result.qd**2, axis=1)
    dissipated = float(np.sum(0.5 * (p[1:] + p[:-1]) * np.diff(result.t)))
    return abs(v[1] - v[0] + dissipated)


def summary(result, baseline: PinocchioModel, config) -> dict:
    """What one executed plan costs and how close it comes (true energy: Pinocchio)."""
    links = closest_link(result, config)
    return {"energy_J": result.energy,
            "true_energy_J": executed_energy(baseline, result.execution, result.t),
            "energy_bound_J": energy_bound(baseline.model, result),
            "end_speed_rad_s": float(np.max(np.abs(result.qd[-1]))),
            "min_clearance_m": float(result.clearance.min()),
            "closest_link": links["closest_link"],
            "end_error_rad": result.end_error, "replans": len(result.execution.segments) - 1,
            "peak_torque_Nm": result.peak_torque.tolist(), "feasible": result.feasible,
            "problems": list(result.problems)}


def plan_checks(name: str, s: dict, threshold: float, rest: bool,
                clearable: bool = True) -> tuple[list[Check], list[Target]]:
    """What one executed plan must show: feasible, at the goal (at rest, spending at least the
    physical bound, when asked to arrive at rest), clear of the obstacle. On a scenario not
    designed to be clearable (clearable False: a robot without a registered motion) the
    clearance is a target, not a check: no path may exist, and a plan saying so is right."""
    clearance = s["min_clearance_m"] >= threshold - CLEARANCE_TOLERANCE
    detail = (f"min clearance {1e3 * s['min_clearance_m']:.1f} mm, threshold "
              f"{1e3 * threshold:.0f} mm")
    problems = [x for x in s["problems"] if clearable or not x.startswith("clearance")]
    checks = [check(f"{name}_feasible", not problems, "; ".join(problems) or "no problem"),
              check(f"{name}_reaches_goal", s["end_error_rad"] <= END_TOLERANCE,
                    f"end error {s['end_error_rad']:.1e} rad")]
    targets = []
    if clearable:
        checks.append(check(f"{name}_clearance_held", clearance, detail))
    else:
        targets.append(Target(f"{name}: smallest clearance, whole path", 1e3 * s["min_clearance_m"],
                              1e3 * (threshold - CLEARANCE_TOLERANCE), "mm",
                              lower_is_better=False))
    if rest:
        checks += [check(f"{name}_ends_at_rest", s["end_speed_rad_s"] <= REST_TOLERANCE,
                         f"end speed {s['end_speed_rad_s']:.1e} rad/s"),
                   check(f"{name}_spends_the_physical_bound",
                         s["true_energy_J"] >= s["energy_bound_J"] - ENERGY_TOLERANCE,
                         f"{s['true_energy_J']:.4f} J spent, |dV + dissipated| = "
                         f"{s['energy_bound_J']:.4f} J")]
    return checks, targets
