"""What `plan` says when the velocity limits block the goal: a longer --duration, with the
shortest one the limits allow (max over joints of |goal - start| / limit on a straight line,
and the peak factor of the planner's polynomial beside)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from harness.cli import main
from harness.plan.messages import (
    infeasible,
    peak_factor,
    polynomial_duration,
    velocity_diagnosis,
    velocity_duration,
)
from harness.robots.registry import erd_robots_dir
from tests.helpers import lynx_config, lynx_scenario

LIMITED = lynx_config(velocity_limit=(0.5, 0.5, 0.5))


def test_the_shortest_duration_is_the_straight_line_at_the_limit():
    s = lynx_scenario()
    shortest, joint = velocity_duration(LIMITED, s)
    assert joint == 0 and shortest == pytest.approx(np.pi / 0.5)
    assert velocity_duration(dataclasses.replace(LIMITED, velocity_limit=None), s) is None


def test_a_too_short_duration_is_diagnosed_with_the_duration_needed():
    message = velocity_diagnosis(LIMITED, lynx_scenario())
    assert "--duration" in message and f"{np.pi / 0.5:.3g} s" in message
    assert "replan-budget" not in message
    assert velocity_diagnosis(LIMITED, dataclasses.replace(lynx_scenario(), duration=9.5)) is None


def test_velocity_problems_suggest_a_longer_duration():
    problems = ["joint 1 velocity 0.8 rad/s exceeds the limit 0.5 rad/s"]
    message = infeasible(problems, LIMITED, dataclasses.replace(lynx_scenario(), duration=7.0))
    assert "a longer --duration" in message and "replan-budget" not in message
    assert "--duration" not in infeasible(["solver failed: x"], LIMITED, lynx_scenario())


def test_cli_velocity_limited_plan_says_duration(tmp_path, capsys):
    out = tmp_path / "plan.json"
    code = main(["plan", "--model", "pinocchio", "--velocity-limit", "0.5,0.5,0.5",
                 "--duration", "2", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code != 0 and not out.exists()
    assert len(err) == 1 and "longer --duration" in err[0] and "6.28 s" in err[0], err


def test_the_peak_factor_is_the_cubics_at_degree_4_and_no_polynomial_beats_it():
    """Degree 4 from rest to rest: every such polynomial is the cubic 3s^2 - 2s^3 plus a
    s^2 (1 - s)^2, whose speed at s = 1/2 is the cubic's 1.5 (closed form). At every degree,
    random polynomials of the family (rest at the goal or not) never peak below the factor,
    and the factor falls with the degree."""
    assert peak_factor(4, True) == pytest.approx(1.5, abs=1e-6)
    rng, s = np.random.default_rng(0), np.linspace(0.0, 1.0, 20001)
    for degree in range(4, 10):
        for rest in (True, False):
            k = np.arange(2, degree + 1)
            equal = np.vstack([np.ones(len(k))] + ([k] if rest else []))
            target = np.r_[1.0, 0.0][: len(equal)]
            particular = np.linalg.lstsq(equal, target, rcond=None)[0]
            null = np.linalg.svd(equal)[2][len(equal):].T
            for _ in range(200):
                c = particular + null @ rng.normal(0.0, 2.0, null.shape[1])
                peak = np.max(np.abs((k * s[:, None] ** (k - 1)) @ c))
                assert peak >= peak_factor(degree, rest) - 1e-9
    factors = [peak_factor(d, True) for d in range(4, 10)]
    assert all(b <= a + 1e-12 for a, b in zip(factors, factors[1:], strict=False))


def test_a_duration_the_straight_line_allows_but_no_plan_can_is_diagnosed():
    """Within the straight line's bound (2 s > pi / 2) but below the degree-4 polynomial's
    (1.5 x pi / 2 = 2.36 s): diagnosed before any search, with both durations."""
    limited = lynx_config(velocity_limit=(2.0, 2.0, 2.0), rest_at_goal=True)  # plan's default
    case = dataclasses.replace(lynx_scenario(), duration=2.0)
    assert velocity_duration(limited, case)[0] < 2.0
    shortest, joint = polynomial_duration(limited, case)
    assert joint == 0 and shortest == pytest.approx(1.5 * np.pi / 2.0, rel=1e-6)
    message = velocity_diagnosis(limited, case)
    assert "1.57 s on a straight line" in message and "2.36 s on the planner's degree-4" in message
    assert velocity_diagnosis(limited, dataclasses.replace(case, duration=2.4)) is None


@pytest.mark.slow
def test_an_execution_the_anytime_sqp_cannot_keep_is_the_penalty_loops(tmp_path, capsys):
    """example-robot-data's TALOS left arm past an obstacle the anytime SQP's re-plans do not
    clear (42 mm at the threshold's 80): plain `plan` writes the penalty loop's execution,
    which keeps the threshold, says so on stderr in one note, and PLAN.json names its
    re-planner; asked for by name, the anytime SQP's failure is the one error line, exit 2."""
    urdf = str(erd_robots_dir() / "talos_data" / "robots" / "talos_left_arm.urdf")
    args = ["plan", "--robot", urdf, "--model", "pinocchio",
            "--start", "0.864,-0.977,-1.649,-1.012,-0.559,-0.279,-0.733",
            "--goal", "2.016,0.977,-0.707,1.012,0.559,0.279,-0.314",
            "--obstacle-from", "0.26,0.9,0.0", "--obstacle-to", "0.26,0.2,0.0"]
    out = tmp_path / "plan.json"
    assert main(args + ["--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    assert plan["replanner"] == "fatrop" and plan["feasible"]
    assert plan["min_clearance"] >= plan["threshold"] - 2e-3
    err = capsys.readouterr().err
    assert err.count("note: the sqp re-planner's execution did not keep the threshold") == 1
    asked = tmp_path / "asked.json"
    assert main(args + ["--replanner", "sqp", "--out", str(asked)]) == 2
    assert not asked.exists()
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "no feasible plan: clearance" in err


def test_a_failure_both_re_planners_had_does_not_suggest_the_other():
    """When plain `plan` has run the penalty loop's execution after the anytime SQP's
    (planning.planners.executed, either) and both missed, the error line says so instead of
    suggesting --replanner fatrop; with the re-planner named it still suggests it."""
    config = dataclasses.replace(lynx_config(), replanner="anytime")
    problems = ("clearance 0.0730 m < threshold 0.08 m - 0.002 m",)
    both, named = infeasible(problems, config, both=True), infeasible(problems, config)
    assert "did not keep the threshold either" in both and "may find one;" in both
    assert "or --replanner fatrop may find one" in named and "either" not in named
    assert both.count("\n") == named.count("\n") == 0


def test_a_first_plan_by_the_other_method_is_recorded(tmp_path, monkeypatch, capsys):
    """The anytime SQP's first plan made infeasible: the first plan is the penalty loop's
    (planning.offline), PLAN.json's first_plan_fallback names it, stderr says so once, and
    the first segment is the penalty loop's though its status reads as any other's
    (#56 item 9)."""
    from planning.bank.planner import BankPlanner

    cold = BankPlanner.plan_cold

    def infeasible_first(self, problem, starts=None):
        best, plans = cold(self, problem, starts)
        return dataclasses.replace(best, success=False, status="forced failure"), plans

    monkeypatch.setattr(BankPlanner, "plan_cold", infeasible_first)
    out = tmp_path / "plan.json"
    assert main(["plan", "--model", "pinocchio", "--no-replan", "--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    assert plan["replanner"] == "sqp" and plan["first_plan_fallback"] == "fatrop"
    assert plan["segments"][0]["status"] != "forced failure"
    notes = [line for line in capsys.readouterr().err.splitlines() if "first plan" in line]
    assert len(notes) == 1 and "fatrop" in notes[0]
