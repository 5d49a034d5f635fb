"""Real-time iterations (PenaltyOptions.replan_iterations): a re-plan's warm solve capped at a
few iterations of CasADi's feasible SQP (planning.penalty.backends "feasiblesqp"), whose
iterate the arm may follow (planning.replanning decides), going on from it at the next obstacle sample."""

from __future__ import annotations

from planning.penalty import backends
from planning.types import ITERATE


def step(solver, args: dict) -> tuple[dict, backends.Stats | None]:
    """One real-time iteration: feasiblesqp capped at config.penalty.replan_iterations from the warm
    start. Its result, with its own status if it converged, with status ITERATE if it stopped
    at the cap; stats None (the caller solves the NLP out from the same start) if the start
    was refused as infeasible or the point it returns leaves the constraints by more than
    backends.FEASIBLE_ITERATE (the next start's tolerance; converged or not)."""
    result = solver(**args)
    stats = backends.stats(solver, args, result)
    if backends.violation(result, args) > backends.FEASIBLE_ITERATE:  # start or iterate out
        return result, None
    if stats.success:
        return result, stats
    if stats.status == "No_Feasible_Initialization":
        return result, None
    # an iterate, or the start itself where its trust region refused the first step: the
    # same motion then, and the next sample tries again on its own problem (solving those
    # out instead costs far more CPU: (docs/realtime.md, 'planning.penalty.realtime_iteration'))
    return result, backends.Stats(True, ITERATE, stats.iterations)
