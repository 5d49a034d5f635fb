"""The planner's one error type: bad input or a plan that cannot be trusted."""


class PlanningError(ValueError):
    """Unreachable goal, start inside the obstacle threshold, bad duration, solver failure."""
