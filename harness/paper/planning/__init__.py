"""The paper's planning reproduction: its parametrizations (variants), the planners it is
compared with (baselines: minimum jerk, scipy trust-constr) and re-plan latency (speed)."""
