"""The real-time SQP: clearance as elastic rows, an anytime trust-region SQP under a CPU
budget, every accepted iterate checked.

- planner: AnytimePlanner, the SQP as a SegmentPlanner (planning.types): budgets, the
  multi-start's shared budget
- solver: Anytime, one plan or re-plan by the SQP under a budget (rounds, screening, choice)
- sqp: the anytime trust-region SQP of the elastic NLP
- elastic_qp, qp_kernels: the QP of one iteration (DAQP) and its array work (numba)
- local_model: the NLP's objective, rows and derivatives at a point, in one function
- safety, candidates: every iterate checked (clearance, limits, torques) and the choice
- budget: the clock a budget counts and the recent costs of a plan's rounds
"""
