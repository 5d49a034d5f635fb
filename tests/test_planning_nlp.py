"""The planning NLP with the torque model called at each sample (large models) against the
same NLP with its expression copied into every sample (small models)."""

from __future__ import annotations

import casadi as ca
import numpy as np

import planning.nlp as nlp_module
from harness.robots.baseline import PinocchioModel
from harness.robots.registry import load_pinocchio
from planning.config import true_energy_config
from planning.nlp import PlanningNLP


def _derivatives(nlp: PlanningNLP) -> ca.Function:
    multipliers = ca.SX.sym("lam", nlp.g.numel())
    lagrangian = nlp.f + ca.dot(multipliers, nlp.g)
    return ca.Function("d", [nlp.x, nlp.p, multipliers],
                       [nlp.f, nlp.g, ca.gradient(nlp.f, nlp.x), ca.jacobian(nlp.g, nlp.x),
                        ca.hessian(lagrangian, nlp.x)[0]])


def test_called_torque_model_is_the_inlined_one(monkeypatch):
    model = PinocchioModel(load_pinocchio("lynxmotion"))
    config = true_energy_config(obstacle_slots=6, energy_samples=8)
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
