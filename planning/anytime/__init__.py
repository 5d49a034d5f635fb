"""The real-time SQP: clearance as elastic rows, an anytime trust-region SQP under a CPU
budget, every accepted iterate checked.

- planner: Anytime, plans and re-plans of Algorithm 2 by the SQP (rounds, screening, choice)
- sqp: the anytime trust-region SQP of the elastic NLP
- elastic_qp, qp_kernels: the QP of one iteration (DAQP) and its array work (numba)
- local_model: the NLP's objective, rows and derivatives at a point, in one function
- safety, candidates: every iterate checked (clearance, limits, torques) and the choice
- budget: the clock a budget counts and the recent costs of a plan's rounds
"""
