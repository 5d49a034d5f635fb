"""The executed trajectory, sampled, scored and checked: what PLAN.json holds."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from identification.torque_model import Motion, TorqueModel
from planning.config import JSON_NAMES, PlannerConfig, Scenario
from planning.formulation.clearance import link_clearances
from planning.formulation.energy import absolute_energy
from planning.formulation.limits import LIMIT_TOLERANCE
from planning.globalsearch.planner import report
from planning.replanning import Execution
from planning.types import DEADLINE

CLEARANCE_TOLERANCE = 2e-3  # m below the threshold still counted as avoided (penalty is soft)
END_TOLERANCE = 1e-6  # rad
# relative: the NLP holds the torque limit at its samples only; between them a plan may
# exceed it by this much (the dense grid has 5 points per obstacle sample interval)
TORQUE_TOLERANCE = 0.01


@dataclass(frozen=True)
class PlanResult(Motion):
    """Executed motion (t, q, qd, qdd) on a time grid that contains every obstacle sample
    time, with what it costs and how close it comes."""

    obstacle: np.ndarray  # (n, 3) m, the obstacle centre at t
    clearance: np.ndarray  # (n, links) m, each moving link (config.geometry.links)
    sample_clearance: np.ndarray  # (K,) m, min over links at the obstacle sample times
    energy: float  # J, integral of |P| on t under the planning model
    end_error: float  # rad, max |q(T) - goal|
    limit_violation: float  # rad, worst excursion beyond the joint limits
    peak_torque: np.ndarray  # (dof,) N m, max |tau_i| on t under the planning model
    execution: Execution
    feasible: bool
    problems: tuple[str, ...]
    peak_velocity: np.ndarray | None = None  # (dof,) rad/s, max |qd_i| on t


def sample_execution(execution: Execution, t: np.ndarray):
    """q, qd, qdd of the concatenated segments at times t (each segment from its start)."""
    starts = np.array([s.trajectory.t_begin for s in execution.segments])
    which = np.searchsorted(starts, t, side="right") - 1
    states = [np.empty((len(t), len(execution.segments[0].trajectory.coefficients)))
              for _ in range(3)]
    for i, segment in enumerate(execution.segments):
        mask = which == i
        if mask.any():
            for out, value in zip(states, segment.trajectory.state(t[mask]), strict=True):
                out[mask] = value
    return tuple(states)


def executed_energy(model: TorqueModel, execution: Execution, t: np.ndarray) -> float:
    """Integral of |P| dt (J) of the concatenated segments, each on the points of the grid t
    inside the interval it was followed plus that interval's ends, from its own polynomial.
    A re-plan keeps position and velocity but changes the acceleration, so the power jumps
    there; a trapezoid across the jump misses by half a step times it
    (docs/realtime.md, 'planning.result')."""
    segments = execution.segments
    starts = [s.trajectory.t_begin for s in segments]
    total = 0.0
    for segment, a, b in zip(segments, starts, [*starts[1:], float(t[-1])], strict=True):
        grid = np.unique(np.concatenate([[a], t[(t > a) & (t < b)], [b]]))
        if len(grid) > 1:
            total += absolute_energy(model, grid, *segment.trajectory.state(grid))
    return total


def evaluate(execution: Execution, scenario: Scenario, model: TorqueModel,
             config: PlannerConfig, refine: int = 5) -> PlanResult:
    """Sample the execution (refine points per obstacle sample interval) and check it."""
    samples = scenario.obstacle.samples if scenario.obstacle else 200
    t = np.linspace(0.0, scenario.duration, refine * samples + 1)
    q, qd, qdd = sample_execution(execution, t)
    obstacle = scenario.obstacle.position(t) if scenario.obstacle else np.full((len(t), 3), np.nan)
    clearance = (link_clearances(config.geometry, q, obstacle) if scenario.obstacle
                 else np.full((len(t), len(config.geometry.links)), np.inf))
    sample_clearance = clearance[refine::refine].min(axis=1)
    end_error = float(np.max(np.abs(q[-1] - np.asarray(scenario.goal))))
    limit = float(max(0.0, np.max(np.asarray(config.lower) - q), np.max(q - np.asarray(config.upper))))
    problems = [f"solver failed: {status}" for status in execution.failures]
    if end_error > END_TOLERANCE:
        problems.append(f"end-position error {end_error:.2e} rad > {END_TOLERANCE:.0e}")
    if limit > LIMIT_TOLERANCE:
        problems.append(f"joint limits exceeded by {limit:.2e} rad")
    peak_torque = np.abs(model.torque(q, qd, qdd)).max(axis=0)
    problems += torque_problems(peak_torque, config.torque_limit)
    peak_velocity = np.abs(qd).max(axis=0)
    problems += _rate_problems(peak_velocity, config.velocity_limit, "velocity", "rad/s")
    problems += _rate_problems(np.abs(qdd).max(axis=0), config.acceleration_limit,
                               "acceleration", "rad/s^2")
    if sample_clearance.min() < config.threshold - CLEARANCE_TOLERANCE:
        k, link = np.unravel_index(np.argmin(clearance[refine::refine]),
                                   clearance[refine::refine].shape)
        problems.append(f"clearance {sample_clearance.min():.4f} m < threshold "
                        f"{config.threshold} m - {CLEARANCE_TOLERANCE} m (link "
                        f"'{config.geometry.link_names[link]}' at t = "
                        f"{t[refine::refine][k]:.3f} s)")
    return PlanResult(t, q, qd, qdd, obstacle, clearance, sample_clearance,
                      executed_energy(model, execution, t), end_error, limit, peak_torque,
                      execution, not problems, tuple(problems), peak_velocity)


def torque_problems(peak: np.ndarray, limit) -> list[str]:
    """One line per joint whose peak torque (N m) exceeds its limit beyond the tolerance."""
    if limit is None:
        return []
    return [f"joint {j + 1} torque {peak[j]:.3g} N m exceeds the limit {limit[j]:g} N m"
            for j in range(len(peak)) if peak[j] > limit[j] * (1 + TORQUE_TOLERANCE)]


def _rate_problems(peak: np.ndarray, limit, what: str, unit: str) -> list[str]:
    """One line per joint whose peak velocity or acceleration exceeds its limit."""
    if limit is None:
        return []
    return [f"joint {j + 1} {what} {peak[j]:.3g} {unit} exceeds the limit {limit[j]:g} {unit}"
            for j in range(len(peak)) if peak[j] > limit[j]]


def to_json(result: PlanResult, scenario: Scenario, config: PlannerConfig,
            model_name: str) -> dict:
    """The PLAN.json payload (CLI contract keys plus descriptive extras)."""
    segments = result.execution.segments
    return {
        "coefficients": [s.trajectory.coefficients for s in segments],
        "coefficient_order": f"per segment (dof, {config.degree + 1}): column p multiplies s**p, "
                             "s = (t - t_begin) / duration",
        "segments": [{"t_begin": s.trajectory.t_begin, "duration": s.trajectory.duration,
                      "objective_energy": s.energy, "penalty": s.penalty,
                      "penalty_weight": s.penalty_weight,
                      "iterations": s.iterations, "status": s.status} for s in segments],
        "t": result.t, "q": result.q, "qd": result.qd, "qdd": result.qdd,
        "obstacle": result.obstacle if scenario.obstacle else None,
        "clearance": result.clearance if scenario.obstacle else None,
        "sample_times": scenario.obstacle.sample_times if scenario.obstacle else None,
        "sample_clearance": result.sample_clearance if scenario.obstacle else None,
        "threshold": config.threshold, "penalty_weight": config.penalty_weight,
        "energy_samples": config.energy_samples,
        "energy_quadrature": config.energy_quadrature, "degree": config.degree,
        "energy": result.energy,
        "min_clearance": float(result.sample_clearance.min()) if scenario.obstacle else None,
        **closest_link(result, config),
        "replans": len(segments) - 1,
        "replan_times": result.execution.replan_times,
        "solve_ms": result.execution.solve_ms,
        "solve_cpu_ms": result.execution.solve_cpu_ms,
        "replan_failures": result.execution.replan_failures,
        "solver": config.penalty.solver, "starts": config.starts,
        "polish": config.penalty.polish, "polish_samples": config.penalty.polish_samples,
        "replan_deadline_ms": config.replan_deadline_ms,
        "replan_iterations": config.penalty.replan_iterations,
        "replanner": JSON_NAMES[config.replanner],  # PLAN.json's names: "fatrop", "sqp"
        # the other method's name when the first plan is its (the replanner's was not
        # feasible, planning.offline), else null
        "first_plan_fallback": result.execution.first_plan_fallback,
        "replan_budget_ms": config.anytime.replan_budget_ms,
        "cold_budget_ms": config.anytime.cold_budget_ms,
        "warm_radius": config.anytime.warm_radius,
        "settle_horizon": config.settle_horizon,
        "iteration_ms": config.anytime.iteration_ms,
        # the budgets' clock: "nominal" (iteration_ms per SQP iteration: the same plan on any
        # machine and load) or "cpu" (plan --realtime)
        "clock": "cpu" if config.anytime.iteration_ms is None else "nominal",
        "global_search": report(config, segments, result.execution.search_failures),
        "bank": result.execution.bank,
        "deadline_misses": sum(f.startswith(DEADLINE) for f in result.execution.replan_failures),
        "timing": timing(result.execution, config),
        "end_error": result.end_error, "limit_violation": result.limit_violation,
        "peak_torque": result.peak_torque, "torque_limit": config.torque_limit,
        "peak_velocity": result.peak_velocity, "velocity_limit": config.velocity_limit,
        "acceleration_limit": config.acceleration_limit,
        "feasible": result.feasible, "problems": result.problems,
        "duration": scenario.duration, "start": scenario.start, "goal": scenario.goal,
        "start_velocity": scenario.start_velocity, "rest_at_goal": config.rest_at_goal,
        "model": model_name, "robot": config.geometry.name,
        "link_radii": config.geometry.link_radii,
        "link_capsules": capsules(config.geometry),
        # m, obstacle centre to the nearest link capsule's surface; null without capsules
        "min_surface_clearance": float(result.sample_clearance.min())
        if scenario.obstacle and config.geometry.radii else None,
    }


def capsules(geometry) -> list[dict] | None:
    """Each link's capsule: the joint moving it (1-based), its axis ends a, b in that joint's
    frame and its radius (m); None where the links are the joint-origin segments."""
    if not geometry.ends:
        return None
    return [{"joint": i + 1, "a": a, "b": b, "radius": radius}
            for (i, _), (a, b), radius in zip(geometry.links, geometry.ends,
                                              geometry.link_radii.tolist(), strict=True)]


TIMING_KEYS = ("solve_ms", "solve_cpu_ms", "timing")  # PLAN.json keys that vary run to run


def timing(execution, config: PlannerConfig) -> dict:
    """Every re-plan's real CPU (ms) against its budget, and what it spent on the budget's
    clock (nominal ms, or CPU under --realtime): whether the iteration budget fits the CPU
    budget on this machine."""
    cpu, clock = execution.solve_cpu_ms[1:], execution.clock_ms[1:]
    budget = config.anytime.replan_budget_ms
    return {"replan_cpu_ms": cpu, "replan_clock_ms": clock, "replan_budget_ms": budget,
            # what a re-plan's times count: a bank's whole work (planning.bank.work) or a solve
            "replan_work": (execution.bank or {}).get("work", "the solve's"),
            "replan_cpu_max_ms": max(cpu, default=None),
            "replans_over_budget": sum(ms > budget for ms in cpu)}


def closest_link(result: PlanResult, config: PlannerConfig) -> dict:
    """Which link came closest to the obstacle, and each link's smallest clearance (m)."""
    names = config.geometry.link_names
    if not np.all(np.isfinite(result.clearance)):
        return {"links": names, "closest_link": None, "link_min_clearance": None}
    per_link = result.clearance.min(axis=0)
    return {"links": names, "closest_link": names[int(np.argmin(per_link))],
            "link_min_clearance": per_link}
