"""The planning NLP with the torque model called at each sample (large models) against the
same NLP with its expression copied into every sample (small models)."""

from __future__ import annotations

import casadi as ca
import numpy as np

import planning.formulation.nlp as nlp_module
from harness.robots.arm import Arm
from planning.formulation.nlp import PlanningNLP
from planning.types import Segment
from tests.helpers import lynx_config, lynx_default_config


def _derivatives(nlp: PlanningNLP) -> ca.Function:
    multipliers = ca.SX.sym("lam", nlp.g.numel())
    lagrangian = nlp.f + ca.dot(multipliers, nlp.g)
    return ca.Function("d", [nlp.x, nlp.p, multipliers],
                       [nlp.f, nlp.g, ca.gradient(nlp.f, nlp.x), ca.jacobian(nlp.g, nlp.x),
                        ca.hessian(lagrangian, nlp.x)[0]])


def test_called_torque_model_is_the_inlined_one(monkeypatch):
    model = Arm.of("lynxmotion").nominal
    config = lynx_default_config(obstacle_slots=6, energy_samples=8)
    inlined = PlanningNLP(model, config)
    monkeypatch.setattr(nlp_module, "INLINE_INSTRUCTIONS", 0)
    called = PlanningNLP(model, config)
    assert inlined.inline and not called.inline
    # the call nodes are really there: the called NLP has fewer SX instructions
    count = lambda n: ca.Function("g", [n.x, n.p], [n.f, n.g]).n_instructions()  # noqa: E731
    assert count(called) < count(inlined)
    rng = np.random.default_rng(3)
    for _ in range(3):
        x = rng.normal(size=inlined.x.numel())
        p = rng.uniform(0.1, 1.0, size=inlined.p.numel())
        lam = rng.normal(size=inlined.g.numel())
        for a, b in zip(_derivatives(inlined)(x, p, lam), _derivatives(called)(x, p, lam),
                        strict=True):
            assert np.allclose(np.asarray(a), np.asarray(b), rtol=1e-10, atol=1e-10)


def test_goal_limit_rows_are_built_only_where_the_goal_is_on_a_limit():
    """A goal inside the limits is solved without the (free) goal-limit rows: the same
    optimum as the NLP with every row; a goal on a limit gets that joint's rows."""
    from planning.config import PenaltyOptions
    from planning.penalty.solver import Planner

    model = Arm.of("lynxmotion").nominal
    planner = Planner(model, lynx_config(penalty=PenaltyOptions(solver="ipopt")))
    start, goal = (1.0, 0.6, -0.8), (-0.5, 1.2, -1.4)
    plan = planner.solve(Segment(start, (0.0, 0.0, 0.0), 0.0, 2.0, goal))
    pruned = planner._relaxed_for(goal).nlp
    assert pruned.quotient_rows == {} and pruned.g.numel() < planner.nlp.g.numel()
    full = ca.nlpsol("full", "ipopt", {"x": planner.nlp.x, "p": planner.nlp.p,
                                       "f": planner.nlp.f, "g": planner.nlp.g},
                     {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
                      "ipopt.tol": 1e-10})
    lbg, ubg = planner.bounds(goal)
    reference = full(x0=planner.initial_guess(start, (0.0,) * 3, 2.0, goal), lbg=lbg, ubg=ubg,
                     p=planner.parameters(start, (0.0,) * 3, 2.0, goal, None))
    assert plan.success  # same optimum (the energy is flat along some directions: to 1e-3)
    assert np.isclose(plan.energy + plan.penalty, float(reference["f"]), rtol=1e-7)
    motion = planner.trajectory(np.asarray(reference["x"]).ravel(), start, (0.0,) * 3, 0.0, 2.0)
    assert np.allclose(plan.trajectory.coefficients, motion.coefficients, rtol=1e-3, atol=1e-6)
    on_limit = (-np.pi / 2, 1.2, -1.4)  # joint 1 on its lower limit
    assert set(planner._relaxed_for(on_limit).nlp.quotient_rows) == {0}
