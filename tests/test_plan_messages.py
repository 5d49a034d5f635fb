"""What `plan` says when the velocity limits block the goal: a longer --duration, with the
shortest one the limits allow (max over joints of |goal - start| / limit)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.cli import main
from harness.commands.plan_messages import infeasible, velocity_diagnosis, velocity_duration
from planning.config import PlannerConfig, Scenario

LIMITED = PlannerConfig(velocity_limit=(0.5, 0.5, 0.5))


def test_the_shortest_duration_is_the_straight_line_at_the_limit():
    s = Scenario()
    shortest, joint = velocity_duration(LIMITED, s)
    assert joint == 0 and shortest == pytest.approx(np.pi / 0.5)
    assert velocity_duration(dataclasses.replace(LIMITED, velocity_limit=None), s) is None


def test_a_too_short_duration_is_diagnosed_with_the_duration_needed():
    message = velocity_diagnosis(LIMITED, Scenario())
    assert "--duration" in message and f"{np.pi / 0.5:.3g} s" in message
    assert "replan-budget" not in message
    assert velocity_diagnosis(LIMITED, dataclasses.replace(Scenario(), duration=7.0)) is None


def test_velocity_problems_suggest_a_longer_duration():
    problems = ["joint 1 velocity 0.8 rad/s exceeds the limit 0.5 rad/s"]
    message = infeasible(problems, LIMITED, dataclasses.replace(Scenario(), duration=7.0))
    assert "a longer --duration" in message and "replan-budget" not in message
    assert "--duration" not in infeasible(["solver failed: x"], LIMITED, Scenario())


def test_cli_velocity_limited_plan_says_duration(tmp_path, capsys):
    out = tmp_path / "plan.json"
    code = main(["plan", "--model", "pinocchio", "--velocity-limit", "0.5,0.5,0.5",
                 "--duration", "2", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code != 0 and not out.exists()
    assert len(err) == 1 and "longer --duration" in err[0] and "6.28 s" in err[0], err
