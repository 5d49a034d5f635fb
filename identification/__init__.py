"""Sparse identification of robot torque models (paper sections II.A-II.F).

- torque_model: the TorqueModel interface every model implements;
- library/: feature libraries and a robot's base atoms (KinematicLibrary);
- regression/: the numeric estimators and the torque regressors (regression.torque: per
  joint, coupled, jointwise, on base atoms; regression.consistent: physically consistent
  with its prior);
- identify: the one front door, identify(q, qd, qdd, tau, library, holdout, tau_clean,
  regressor); choice: which library, prior and regressor the CLI's names mean;
- feature_model, kinematic_model: the two identified model kinds; model: MODEL.json read
  and written for both;
- friction, physical: friction laws and the physically consistent fit; closeloop/: the
  loop closed on residuals.
"""
