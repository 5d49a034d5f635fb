"""Sparse identification of robot torque models (paper sections II.A-II.F).

Public names: the TorqueModel interface, the identified model and its
MODEL.json reader/writer, libraries, denoising, sparse regression and the
identification pipeline (per-joint as in the paper, or coupled: one Lagrangian shared
by all joints).
"""

from identification.coupled import AtomBasis, CoupledRegression
from identification.denoise import Denoised, denoise
from identification.errors import IdentificationError, LibraryRankWarning
from identification.identify import Identification, identify
from identification.libraries import generic_library, paper_library
from identification.library import Library
from identification.model import IdentifiedModel, JointModel, load_model, model_from_dict
from identification.prior_knowledge import prior_knowledge_library
from identification.sparse import SparseRegression
from identification.torque_model import TorqueModel, as_states

__all__ = [
    "AtomBasis", "CoupledRegression", "Denoised", "IdentificationError", "Identification",
    "IdentifiedModel", "JointModel",
    "Library", "LibraryRankWarning", "SparseRegression", "TorqueModel", "as_states", "denoise",
    "generic_library", "identify", "load_model", "model_from_dict", "paper_library",
    "prior_knowledge_library",
]
