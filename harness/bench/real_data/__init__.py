"""Bench section (entry point: .section.run): a real Franka Emika Panda's measured log
(Gaz et al. 2019, shipped in data/panda_gaz2019): ingested, identified with the Panda's
kinematics, compared with the nominal URDF model and the least-squares reference, and the
loop closed on it."""
