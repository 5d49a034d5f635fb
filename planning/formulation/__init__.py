"""The planning problem (paper III.B, eqs. 11-19), whichever solver solves it.

- trajectory: joint polynomials in normalized time (eqs. 11, 12), quartic by default
- quadrature, breaks: where the power is sampled for the energy (eq. 18, Gauss, or split at
  the power's sign changes)
- kinematics, clearance, obstacle: link points of any serial arm, the obstacle-to-link-segment
  distance, the moving obstacle and its constant-velocity prediction
- limits: joint limits along a segment, a goal on a limit included
- energy: the energy of a motion under a torque model (J)
- nlp: energy sigma/N sum |P| + alpha max(0, lambda - d)^2 (or clearance as elastic rows)
  with joint and torque limits, built once as CasADi functions
- problem: the numbers of one segment's NLP (parameters, bounds, start points, motions)
- screening: which obstacle samples a solve must see
- compiled: the NLP's functions compiled to machine code, cached per problem (quick -O0
  builds where no CPU time decides a plan, optimized ones otherwise); c_units: a large
  function's generated C split into units built in parallel
"""
