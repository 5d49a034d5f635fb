"""A feature library Theta(q, qd, qdd): named columns, numeric and symbolic."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from identification.errors import IdentificationError, LibraryRankWarning
from identification.library.features import Feature


@dataclass(frozen=True)
class Library:
    """An ordered, duplicate-free set of features for a dof-joint system."""

    name: str
    dof: int
    features: tuple[Feature, ...]
    atoms: tuple = ()  # Lagrangian atoms (prior_knowledge.Atom) it was derived from, if any

    def __post_init__(self) -> None:
        unique = tuple(dict.fromkeys(self.features))
        object.__setattr__(self, "features", unique)

    def __len__(self) -> int:
        return len(self.features)

    def __add__(self, other: Library) -> Library:
        return Library(f"{self.name}+{other.name}", self.dof, self.features + other.features)

    @property
    def names(self) -> list[str]:
        return [f.name for f in self.features]

    def evaluate(self, q, qd, qdd) -> np.ndarray:
        """Theta of shape (n, len(self)) at states of shape (n, dof)."""
        return np.column_stack([f.evaluate(q, qd, qdd) for f in self.features])

    def joint_designs(self, q, qd, qdd) -> list[np.ndarray]:
        """Per joint, the (n, p_j) columns a regression of that joint alone sees: every
        feature, the same for every joint."""
        return [self.evaluate(q, qd, qdd)] * self.dof

    def symbolic(self, q, qd, qdd) -> list:
        """The features as CasADi expressions of column vectors q, qd, qdd."""
        import casadi

        return [f.evaluate(q, qd, qdd, lib=casadi) for f in self.features]

    def subset(self, names: list[str]) -> Library:
        """The library restricted to the named features, in the given order."""
        by_name = {f.name: f for f in self.features}
        missing = [n for n in names if n not in by_name]
        if missing:
            raise IdentificationError(f"features not in library {self.name}: {missing}")
        return Library(self.name, self.dof, tuple(by_name[n] for n in names))


@dataclass(frozen=True)
class Conditioning:
    """Rank and condition number of the column-normalized library on some data."""

    rank: int
    size: int
    condition: float
    collinear: tuple[str, ...]  # features whose removal restores full rank


def conditioning(theta: np.ndarray, names: list[str], rtol: float = 1e-10) -> Conditioning:
    """Condition number of Theta with unit-norm columns, and the collinear features.

    Collinear features are found by QR with column pivoting: the columns the
    pivoting puts last, beyond the numerical rank.
    """
    import scipy.linalg

    norms = np.linalg.norm(theta, axis=0)
    if np.any(norms == 0):
        zero = [n for n, v in zip(names, norms, strict=True) if v == 0]
        return Conditioning(len(names) - len(zero), len(names), float("inf"), tuple(zero))
    scaled = theta / norms
    sv = np.linalg.svd(scaled, compute_uv=False)
    rank = int(np.sum(sv > rtol * sv[0]))
    collinear: tuple[str, ...] = ()
    if rank < len(names):
        _, _, perm = scipy.linalg.qr(scaled, mode="economic", pivoting=True)
        collinear = tuple(names[i] for i in perm[rank:])
    return Conditioning(rank, len(names), float(sv[0] / sv[-1]), collinear)


def warn_if_rank_deficient(cond: Conditioning) -> None:
    """Warn (LibraryRankWarning) naming the collinear features."""
    if cond.rank < cond.size:
        shown = ", ".join(cond.collinear[:8]) + (" ..." if len(cond.collinear) > 8 else "")
        warnings.warn(
            f"library is rank deficient on this data (rank {cond.rank}/{cond.size}); "
            f"collinear features: {shown}",
            LibraryRankWarning,
            stacklevel=3,
        )
