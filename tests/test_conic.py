"""Every LMI fit falls back from Clarabel to SCS where the user sees it (a warning naming the
fit), never silently."""

from __future__ import annotations

import cvxpy as cp
import numpy as np
import pytest

from identification.conic import solve_conic
from tests.helpers import fail_clarabel


def test_a_failed_clarabel_solve_is_said_and_scs_solves(monkeypatch):
    x = cp.Variable((2, 2), PSD=True)
    problem = cp.Problem(cp.Minimize(cp.sum_squares(x - np.diag([1.0, -1.0]))))
    assert solve_conic(problem, "the test fit") == "CLARABEL"
    fail_clarabel(monkeypatch)
    with pytest.warns(RuntimeWarning, match="the test fit's Clarabel solve failed.*SCS"):
        assert solve_conic(problem, "the test fit") == "SCS"
    np.testing.assert_allclose(x.value, np.diag([1.0, 0.0]), atol=1e-3)


def test_an_inaccurate_clarabel_solve_is_said_naming_the_fit(monkeypatch):
    """Clarabel stopped short (here by its iteration cap): one RuntimeWarning naming the fit,
    not cvxpy's generic advice to try another solver (it reached a user of `closeloop`), and
    once a fit however often it is solved."""
    import warnings

    x = cp.Variable((2, 2), PSD=True)
    problem = cp.Problem(cp.Minimize(cp.sum_squares(x - np.diag([1.0, -1.0]))))
    solve = cp.Problem.solve
    monkeypatch.setattr(cp.Problem, "solve", lambda self, **kw: solve(self, max_iter=2, **kw))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert solve_conic(problem, "the test fit") == "CLARABEL"
        assert solve_conic(problem, "the test fit") == "CLARABEL"  # said once a fit
    said = [str(w.message) for w in caught]
    assert len(said) == 1 and said[0].startswith("the test fit: Clarabel stopped short"), said
