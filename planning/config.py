"""Configuration of the planner and of a planning scenario. The arm (its links and limits)
and the motion have no defaults here: they are a robot's (the paper's Lynxmotion and its
scenario: harness.paper.planning.scenario)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from planning.errors import PlanningError
from planning.formulation.kinematics import ArmGeometry
from planning.formulation.obstacle import LinearObstacle

REPLANNERS = ("penalty", "anytime")
RATE_MARGIN = 0.98  # velocity and acceleration rows bound at this fraction of the limits
# the replanners' earlier names, still accepted (`plan --replanner fatrop`); PLAN.json keeps them
ALIASES = {"fatrop": "penalty", "sqp": "anytime"}
JSON_NAMES = {"penalty": "fatrop", "anytime": "sqp"}


@dataclass(frozen=True)
class PenaltyOptions:
    """The paper's exterior penalty loop (planning.penalty; paper III.G): while a solution dips
    more than PlannerConfig.penalty_tolerance (m) below the threshold, alpha is multiplied by
    growth, up to max_weight (J/m^2 per obstacle sample); each solve by one NLP solver."""

    growth: float = 10.0
    max_weight: float = 2e5
    solver: str = "fatrop"  # planning.penalty.backends: "fatrop", "sqpmethod" or "ipopt"
    hessian: str = "exact"  # or "limited-memory" (IPOPT, sqpmethod)
    dual_warm_start: bool = True  # warm re-plans also start from the last multipliers
    max_iterations: int = 300
    warm_max_iterations: int = 60  # a warm solve that needs more restarts cold
    # real-time iterations: a warm re-plan of Algorithm 2 first takes this many iterations of
    # CasADi's feasible SQP from the last plan (planning.penalty.backends "feasiblesqp": every
    # iterate satisfies the constraints) and the arm follows the iterate if it keeps the
    # threshold and the limits; the next obstacle samples go on from it until it converges.
    # An iterate that dips or leaves a limit is solved on to convergence as without them.
    # None: every re-plan is solved to convergence.
    replan_iterations: int | None = None
    # the best `polish` distinct cold plans are solved again, warm, with the split quadrature
    # at polish_samples nodes (planning.formulation.breaks; the sample count a multiple of
    # power_breaks + 1) and the plan that spends least kept: the many-start search runs on
    # the cheap rule (the anytime SQP's cold plans too: planning.penalty.polish)
    polish: int = 0
    polish_samples: int = 40


@dataclass(frozen=True)
class AnytimeOptions:
    """The anytime SQP (planning.anytime): clearance as elastic rows, every plan under a CPU
    budget (ms)."""

    replan_budget_ms: float = 10.0  # CPU per re-plan (one obstacle sample period)
    cold_budget_ms: float = 25.0  # CPU for a first plan, all its starts together
    # reproducible runs: each SQP iteration counts this many ms of the budgets above whatever
    # CPU it took, as do a second-order correction and each half of a plan's round
    # (planning.anytime.budget.Clock): the same plans on a loaded machine (the bench's
    # executed plans). None: the budgets are CPU time of the planning thread (real time)
    iteration_ms: float | None = None
    elastic_weight: float = 1e3  # J per m of clearance missed, per sample and link
    replan_starts: int = 0  # a re-plan also solves from this many cold start points
    # the trust region's first radius in a warm re-plan (the box on the coefficients; a cold
    # plan starts at planning.anytime.sqp.COLD_RADIUS)
    warm_radius: float = 0.5


@dataclass(frozen=True)
class GlobalSearchOptions:
    """A global search beside the anytime SQP's re-plans (planning.globalsearch): the latest
    forecast solved from many starts (the obstacle passed on each side, above and below;
    seeded random starts; the last plan), each to convergence, its best plan offered to the
    real-time loop, which adopts it when, re-solved warm within its budget, it spends less on
    the current forecast and keeps the clearance.

    On the nominal clock (AnytimeOptions.iteration_ms) a search runs on the forecast of the
    re-plan at obstacle sample k, and each plan it finds better than those before is offered
    at sample k + lag, or later when the search's iterations up to it on that clock take
    longer (the same plan on any machine); under CPU clocks (plan --realtime) it runs in
    another process, which sends each better plan back as it finds it (with one core the
    real-time loop runs alone)."""

    enabled: bool = False
    # obstacle samples between a search's forecast and its offer at the least (the search
    # planned from where the plan followed will be then); on the nominal clock each offer
    # enters when the search's work up to it on that clock is done, if that is later
    lag: int = 10
    random_starts: int = 4  # seeded random start points beside the detours
    # the detours: each of the first side_joints joints swung by +-detour_rad at mid-horizon
    # (the base: either side; shoulder and elbow: above, below)
    side_joints: int = 3
    detour_rad: float = 0.5
    solver: str = "sqp"  # each start to convergence by the anytime SQP, or "ipopt"
    # under CPU clocks, searches in another process; False: as on the nominal clock (in
    # this thread, offered lag samples later: the realtime study's stand-in for the other
    # core, its executions running faster than real time)
    background: bool = True


def nominal_iteration_ms(dof: int) -> float:
    """What one anytime-SQP iteration counts on the deterministic clock (AnytimeOptions.
    iteration_ms, ms) on an arm of `dof` joints: 0.5 ms at 3 joints, growing as dof^1.5 (the
    QP and the site evaluations grow with the coefficients), so that a CPU budget's
    iterations about fit it on a reference machine; fixed, not measured per machine, so
    that a command gives the same plan anywhere (docs/realtime.md, 'Deterministic budgets')."""
    return round(0.5 * (dof / 3) ** 1.5, 3)


@dataclass(frozen=True)
class BankOptions:
    """A bank of plans, one per homotopy class of the motion around the obstacle, re-planned
    warm at every obstacle sample, the cheapest followed (planning.bank). size 1: one plan,
    Algorithm 2 as the paper's."""

    size: int = 1  # classes held at most
    # the share of a re-plan's budget the plan followed gets when the bank holds others
    followed_share: float = 0.5
    # the arm switches class when another plan's energy to go is lower by this fraction
    hysteresis: float = 0.01
    # forecasts in a row a class's plan may miss the threshold on before it is dropped
    patience: int = 20
    # the global search's iterations per start before its finalists (it hands every plan to
    # the bank as it goes: a shallower screen hands the classes over sooner)
    screen_iterations: int = 10
    # the other classes' re-plans from a plan that keeps the threshold held in their class by
    # linear guidance (planning.formulation.guidance; the plan followed is re-planned free):
    # off by default, as measured on the development scenarios (docs/realtime.md, 'Guidance')
    guided: bool = False


@dataclass(frozen=True, kw_only=True)
class PlannerConfig:
    """How trajectories are scored and constrained (the formulation), which segment planner
    plans them (replanner) and each planner's options.

    threshold: lambda (m); penalty_weight: alpha (J/m^2 per obstacle sample);
    penalty_tolerance: m a plan may dip below the threshold and still keep it;
    energy_samples: N, weighted by energy_quadrature; degree: of the joint polynomials;
    obstacle_slots: how many obstacle samples one solve sees (the
    ones that can come within the threshold, see planning.formulation.screening);
    limits in rad, enforced at limit_samples interior points of every segment;
    velocity_limit, acceleration_limit: per joint (rad/s, rad/s^2), None: unconstrained;
    torque_limit: |tau_i| <= torque_limit[i] (N m, planning model's torque) at s = 0, the
    energy samples and the obstacle samples of every segment (None: unconstrained; callers
    that know the plant pass its own: planning does not read models).
    geometry (the links clearance is kept for), lower and upper are the arm's: required.
    replanner: "penalty" (the paper's exterior penalty loop, planning.penalty; alias
    "fatrop") or "anytime" (the anytime SQP, planning.anytime; alias "sqp").
    """

    threshold: float = 0.08
    penalty_weight: float = 200.0
    penalty_tolerance: float = 1e-3
    # the paper's (eq. 18, N = 10); `plan` and the bench default to true_energy_config()
    energy_samples: int = 10
    # planning.formulation.quadrature: "paper" (eq. 18), "gauss", "simpson", "split"
    energy_quadrature: str = "paper"
    power_breaks: int = 7  # "split": intervals of the quadrature = power_breaks + 1
    degree: int = 4  # of the joint polynomials (paper: 4); degree - 1 free coefficients per joint
    obstacle_slots: int = 24
    # zero velocity at the goal. The paper's formulation leaves it free (the default here);
    # its optimum may arrive moving, which no real arm can execute and whose energy leaves out
    # the braking: `plan`, the bench and true_energy_config() arrive at rest
    rest_at_goal: bool = False
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    limit_samples: int = 8
    torque_limit: tuple[float, ...] | None = None
    # |qd_i| <= velocity_limit[i] (rad/s) and |qdd_i| <= acceleration_limit[i] (rad/s^2) at
    # rate_samples interior points of every segment, each within RATE_MARGIN of its bound so
    # the motion between the points keeps it (None: unconstrained)
    velocity_limit: tuple[float, ...] | None = None
    acceleration_limit: tuple[float, ...] | None = None
    rate_samples: int = 24
    geometry: ArmGeometry  # links for clearance
    power_smoothing: float = 0.0  # W; 0: exact epigraph of |P|, > 0: sqrt(P^2 + eps^2) - eps
    compile_code: bool = False  # NLP functions as C compiled once (planning.formulation.compiled)
    # built at -O0 when not cached optimized: quick to build, slower to run, the same
    # numbers; for plans no CPU time decides (planning.formulation.compiled.QUICK_FLAGS)
    quick_build: bool = False
    starts: int = 1  # cold plans solve from this many start points (planning.starts)
    # a re-plan still unfinished after this much CPU time of the planning thread (ms) is
    # abandoned and the arm keeps its last plan (Algorithm 2); None: no deadline
    replan_deadline_ms: float | None = None
    # s before the end within which an unconverged plan (ITERATE) is followed as it is, not
    # gone on from, nor re-planned for a global search's offer: a re-plan that short can only
    # reshape the stop, into a violent one (docs/realtime.md, 'The last re-plans'); a stale
    # plan (a dip below the threshold, a detour left) is still re-planned
    settle_horizon: float = 0.2
    # how Algorithm 2 plans and re-plans (planning.planners.segment_planner)
    replanner: str = "penalty"
    penalty: PenaltyOptions = field(default_factory=PenaltyOptions)
    anytime: AnytimeOptions = field(default_factory=AnytimeOptions)
    global_search: GlobalSearchOptions = field(default_factory=GlobalSearchOptions)
    bank: BankOptions = field(default_factory=BankOptions)

    def __post_init__(self):
        name = ALIASES.get(self.replanner, self.replanner)
        if name not in REPLANNERS:
            raise ValueError(f"replanner must be one of {REPLANNERS + tuple(ALIASES)}, got "
                             f"'{self.replanner}'")
        object.__setattr__(self, "replanner", name)

    def with_penalty(self, **changes) -> PlannerConfig:
        """This configuration with these penalty-loop options changed."""
        return dataclasses.replace(self, penalty=dataclasses.replace(self.penalty, **changes))

    def with_anytime(self, **changes) -> PlannerConfig:
        """This configuration with these anytime-SQP options changed."""
        return dataclasses.replace(self, anytime=dataclasses.replace(self.anytime, **changes))

    def with_bank(self, **changes) -> PlannerConfig:
        """This configuration with these bank options changed."""
        return dataclasses.replace(self, bank=dataclasses.replace(self.bank, **changes))

    def with_global_search(self, **changes) -> PlannerConfig:
        """This configuration with these global-search options changed."""
        return dataclasses.replace(self, global_search=dataclasses.replace(self.global_search,
                                                                           **changes))


# what true_energy_config changes of PlannerConfig's defaults
TRUE_ENERGY = dict(energy_quadrature="gauss", energy_samples=20, starts=4, rest_at_goal=True,
                   replanner="anytime", global_search=GlobalSearchOptions(enabled=True),
                   bank=BankOptions(size=4))


def true_energy_config(geometry: ArmGeometry, lower, upper, **changes) -> PlannerConfig:
    """What `torquebench plan` and the bench plan with by default: the true energy (Gauss-
    Legendre, N = 20; eq. 18 with N = 10 lets the optimizer hide negative power between its
    samples), the best of 4 cold starts (the landscape has local optima), at rest at the
    goal, planned and re-planned by the anytime SQP under a CPU budget with its global search
    beside (docs/realtime.md, 'planning.globalsearch'; the paper's penalty loop: replanner
    "penalty"), on the arm of this geometry and joint limits (rad)."""
    return PlannerConfig(**{"geometry": geometry, "lower": tuple(lower), "upper": tuple(upper),
                            **TRUE_ENERGY, **changes})


@dataclass(frozen=True)
class Scenario:
    """Where the arm goes and what crosses its way (rad, rad/s, s, m): a robot's motion
    (the paper's: harness.paper.planning.scenario.paper_scenario)."""

    start: tuple[float, ...]
    goal: tuple[float, ...]
    duration: float
    obstacle: LinearObstacle | None = None
    start_velocity: tuple[float, ...] | None = None  # one per joint; None: at rest

    def __post_init__(self):
        if self.start_velocity is None:
            object.__setattr__(self, "start_velocity", (0.0,) * len(self.start))

    def validate(self, config: PlannerConfig) -> None:
        """Raise PlanningError on input no plan can satisfy."""
        values = np.concatenate([self.start, self.goal, self.start_velocity, [self.duration]])
        if not np.all(np.isfinite(values)):
            raise PlanningError("start, goal, start velocity and duration must be finite")
        if not self.duration > 0:
            raise PlanningError(f"duration must be > 0 s, got {self.duration}")
        lower, upper = np.asarray(config.lower), np.asarray(config.upper)
        if config.geometry.dof != len(lower):
            raise PlanningError(f"the arm has {config.geometry.dof} joints, the limits "
                                f"{len(lower)}")
        for name, q in (("start", self.start), ("goal", self.goal),
                        ("start velocity", self.start_velocity)):
            q = np.asarray(q, float)
            if len(q) != len(lower):
                raise PlanningError(f"{name} must have {len(lower)} values (one per joint), "
                                    f"got {len(q)}")
            if name == "start velocity":
                continue
            bad = np.flatnonzero((q < lower - 1e-9) | (q > upper + 1e-9))
            if bad.size:
                i = bad[0]
                raise PlanningError(
                    f"{name} q{i + 1} = {q[i]:.4f} rad is outside the joint limits "
                    f"[{lower[i]:.4f}, {upper[i]:.4f}]"
                )
        if self.obstacle is not None and abs(self.obstacle.duration - self.duration) > 1e-12:
            raise PlanningError("the obstacle path must span the motion's duration")
