"""Sparse identification of robot torque models (paper sections II.A-II.F).

Public names: the TorqueModel interface, the identified model and its
MODEL.json reader/writer, libraries, denoising, sparse regression and the
identification pipeline (per-joint as in the paper, or coupled: one Lagrangian shared
by all joints).
"""
