"""Sparse identification of robot torque models (paper sections II.A-II.F)."""

from identification.torque_model import TorqueModel, as_states

__all__ = ["TorqueModel", "as_states"]
