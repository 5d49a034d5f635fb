"""Sparse identification of robot torque models (paper sections II.A-II.F)."""

from identification.errors import IdentificationError, LibraryRankWarning
from identification.torque_model import TorqueModel, as_states

__all__ = ["IdentificationError", "LibraryRankWarning", "TorqueModel", "as_states"]
