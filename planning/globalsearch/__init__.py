"""The global search beside the real-time loop (GlobalSearchOptions): a slower
loop that solves the latest forecast from many starts to convergence and offers its best
plan to the anytime SQP's re-plans, which adopt it when it wins on the current forecast.

- starts: the start points: the obstacle passed on each side, above and below (detours),
  seeded random starts, the last plan
- multistart: every start solved to convergence by the anytime SQP or by IPOPT (ipopt: the
  elastic NLP, screened in rounds) and the best kept by one measure on the whole forecast
- planner: GlobalSearchPlanner, a SegmentPlanner (planning.types) around the real-time one:
  when searches run (on the nominal clock at fixed obstacle samples; under CPU clocks in
  another process, background) and the adoption rule
"""
