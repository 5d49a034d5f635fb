"""Energy-optimal, obstacle-avoiding trajectory planning (paper III.B, III.G, Algorithm 2).

Sub-packages, in the order the math flows:

- formulation/: the problem, whichever solver solves it: joint polynomials (trajectory),
  where the power is sampled (quadrature, breaks), the arm's links (kinematics) and their
  distance to the obstacle (clearance, obstacle), joint limits (limits), energy, the NLP
  (nlp) and its numbers for one segment (problem), which obstacle samples a solve sees
  (screening), its functions compiled to C (compiled, c_units)
- penalty/: the paper's exterior penalty loop, a SegmentPlanner (planner): the NLP solver
  built once and warm-started (solver, backends: fatrop, sqpmethod or IPOPT;
  realtime_iteration: capped feasible-SQP steps), the loop raising alpha until the plan
  keeps the threshold (loop) and polishing of cold plans (polish)
- anytime/: the real-time SQP, a SegmentPlanner (planner): clearance as elastic rows, a
  trust-region SQP under a CPU budget (solver, sqp, elastic_qp, qp_kernels, local_model,
  budget), every iterate checked by compiled functions (safety, candidates)
- globalsearch/: the global search beside the anytime SQP's re-plans, a SegmentPlanner around
  it (planner): many starts (starts) solved to convergence by the SQP or IPOPT (multistart,
  ipopt), offered a fixed number of obstacle samples later or from another process
  (background), adopted when they win on the current forecast

Modules at the top:

- types: what both solvers share: the SegmentPlanner protocol (plan(problem, warm) ->
  SegmentPlan) and a segment to plan (Segment), SegmentPlan, ObstacleForecast, the re-plan
  statuses (ITERATE, DEADLINE, LATE)
- planners: the one factory choosing the SegmentPlanner a configuration asks for, its
  offline variant and the plan command's execution (executed)
- offline: cold plans to convergence, falling back to the other method
- config: PlannerConfig (the formulation and the replanner) with its PenaltyOptions,
  AnytimeOptions and GlobalSearchOptions, and Scenario; errors: PlanningError
- starts: the multi-start's start points and the ranking of cold plans
- replanning: Algorithm 2, re-planning from the current state when the obstacle threatens,
  with any SegmentPlanner
- result: the executed trajectory, checked, and its PLAN.json payload
- control: the executed trajectory at a controller's rate with its feed-forward torque
- scenarios: named scenarios; timing: wall and CPU clocks of a plan

The planner takes any `identification.torque_model.TorqueModel` (identified or closed form).
"""
