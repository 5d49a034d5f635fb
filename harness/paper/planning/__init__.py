"""The paper's planning reproduction: its parametrizations (variants) and the planners it is
compared with (baselines: minimum jerk, scipy trust-constr). Re-plan latency, which the
bench's planning section measures on every robot, is harness.plan.speed."""
