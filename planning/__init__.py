"""Energy-optimal, obstacle-avoiding trajectory planning (paper III.B, III.G, Algorithm 2).

Modules, in the order the math flows:

- trajectory: joint polynomials in normalized time (eqs. 11, 12), quartic by default
- quadrature: where the power is sampled for the energy (eq. 18 or a dense rule)
- kinematics, clearance: link points of any serial arm (data from the harness; the
  Lynxmotion's eqs. 9, 10 as one chain) and the obstacle-to-link-segment distance
- obstacle: the moving obstacle, its K samples and its constant-velocity prediction
- nlp, limits: energy sigma/N sum |P| + alpha max(0, lambda - d)^2 with joint limits
- solver: IPOPT through CasADi (exact derivatives), built once, warm-started
- screening: which obstacle samples a solve must see
- segments, replanning: one segment planned (penalty loop or anytime SQP); Algorithm 2,
  re-planning from the current state when the obstacle threatens
- anytime, sqp, elastic_qp, safety: clearance as elastic rows, an anytime trust-region SQP
  under a CPU budget (DAQP on its QPs), every iterate checked by compiled functions
- result: the executed trajectory, checked, and its PLAN.json payload
- baselines, speed, scenarios: minimum jerk, scipy trust-constr, timings, named scenarios

The planner takes any `identification.TorqueModel` (identified or closed form).
"""
