"""The paper's exterior penalty loop (III.G): alpha raised while the plan dips below the
threshold.

- solver: Planner, the planning NLP solved by one backend, built once, warm-started, with an
  IPOPT rescue and torque rows on need
- backends: fatrop, sqpmethod, IPOPT (and feasiblesqp for real-time iterations) option sets
- realtime_iteration: a re-plan's warm solve capped at a few feasible-SQP iterations
- loop: one segment planned by the loop (screened solves, alpha raised, limits settled) and
  the multi-start cold plan, polished or not
- planner: PenaltyLoop, the loop as a SegmentPlanner (planning.types)
- polish: Polished, another SegmentPlanner's cold plans polished by the loop
"""
