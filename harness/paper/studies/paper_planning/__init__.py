"""Study `paper_planning` (entry point: .section.run): energy-optimal planning with moving-obstacle
avoidance (paper III.G).

Plans the paper's scenario with the closed-form (Pinocchio) model and, when one is
given, the identified model; evaluates every executed trajectory's energy with
Pinocchio on a 2 ms grid; adds a scenario whose obstacle crosses the optimal path,
a minimum-jerk comparison, an N = 10 vs N = 40 energy-sample comparison, the
solver timings (cold plans, warm re-plans, scipy trust-constr on the same NLP), the
paper's parametrization against dense quadrature and higher degrees (true energy
against the net-work lower bound), and a swaying obstacle that forces repeated
re-planning.
"""
