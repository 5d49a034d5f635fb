"""A bank of plans, one per homotopy class around the obstacle (planning.bank.planner)."""
