"""Joint friction laws a fit can choose among, per joint, by held-out error.

Every law is viscous + offset (the kinematic library's `viscous` atom and the fitted
intercept), most with Coulomb (its `coulomb` atom), plus at most one column of its own,
linear in its coefficient once its shape is fixed; the shape is taken from a grid by the
same validation that chooses the law:

- viscous: no Coulomb (a joint whose data show none: a Coulomb coefficient held >= 0 fits
  the noise one way and misses other motions, docs/identification.md,
  'identification.friction');
- viscous-coulomb: viscous and Coulomb, nothing more;
- stribeck (v_s): + F_s sign(qd) exp(-(qd / v_s)^2), the static friction's excess over
  Coulomb at low speed (Stribeck, Armstrong-Helouvry 1994), F_s >= 0;
- sigmoid (slope, shift): the Coulomb atom replaced by Gaz et al.'s (2019) friction of the
  Panda, phi / (1 + exp(-slope (qd + shift))) - phi / (1 + exp(-slope shift)), phi >= 0:
  an asymmetric, smooth Coulomb that is zero at rest.

The column is written once for numpy and CasADi (the `lib` argument), so the planner
differentiates the law the fit chose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import expit

from identification.errors import IdentificationError
from identification.library.kinematic import COULOMB_WIDTH

STRIBECK_SPEEDS = (0.01, 0.03, 0.1)  # rad/s
SIGMOID_SLOPES = (3.0, 10.0, 30.0, 100.0)  # s/rad
SIGMOID_SHIFTS = (-0.03, 0.0, 0.03)  # rad/s
LAWS = ("viscous", "viscous-coulomb", "stribeck", "sigmoid")
DESCRIPTIONS = {  # MODEL.json's friction entries, for people
    "viscous": "viscous friction only (the joint's viscous atom, N m s/rad): no shape "
               "parameters, so shape is []",
    "viscous-coulomb": "viscous and Coulomb friction (the joint's viscous and coulomb atoms): "
                       "no shape parameters, so shape is []",
    "stribeck": "viscous + Coulomb + a Stribeck term F_s sign(qd) exp(-(qd / v_s)^2) (its "
                "coefficient F_s in N m): shape is [v_s] in rad/s",
    "sigmoid": "viscous + Gaz et al.'s sigmoid Coulomb phi (s(slope (qd + shift)) - "
               "s(slope shift)) in place of the coulomb atom (phi in N m): shape is [slope "
               "in s/rad, shift in rad/s]",
}


def sigmoid_friction(qd: np.ndarray, steepness: float, shift: float) -> np.ndarray:
    """Gaz et al.'s friction at unit phi1: s(phi2 (qd + phi3)) - s(phi2 phi3), 0 at rest."""
    return expit(steepness * (qd + shift)) - expit(steepness * shift)


@dataclass(frozen=True)
class FrictionLaw:
    """One joint's law: its name and its shape (stribeck: (v_s,); sigmoid: (slope, shift))."""

    name: str = "viscous-coulomb"
    shape: tuple[float, ...] = ()

    def __post_init__(self):
        sizes = {"viscous": 0, "viscous-coulomb": 0, "stribeck": 1, "sigmoid": 2}
        if self.name not in sizes:
            raise IdentificationError(f"unknown friction law {self.name!r} (one of {', '.join(LAWS)})")
        if len(self.shape) != sizes[self.name] or not all(np.isfinite(self.shape)):
            raise IdentificationError(f"friction law {self.name} needs {sizes[self.name]} finite "
                                      f"shape values, got {list(self.shape)}")
        if self.name == "stribeck" and self.shape[0] <= 0:
            raise IdentificationError("a Stribeck speed must be positive")

    @property
    def has_column(self) -> bool:
        return self.name not in ("viscous", "viscous-coulomb")

    @property
    def keeps_coulomb(self) -> bool:
        """The sigmoid takes the Coulomb atom's place, viscous has none; the others add to it."""
        return self.name not in ("viscous", "sigmoid")

    def column(self, qd, lib=np):
        """The law's own column at joint velocities qd (array or CasADi expression)."""
        if self.name == "stribeck":
            (speed,) = self.shape
            return qd / lib.sqrt(qd**2 + COULOMB_WIDTH**2) * lib.exp(-(qd / speed) ** 2)
        if self.name == "sigmoid":
            slope, shift = self.shape
            if lib is np:
                return sigmoid_friction(qd, slope, shift)
            # the logistic as tanh: 1 / (1 + exp(-x)) overflows at large |x| and its
            # derivative, inf / inf, is NaN (a plan's NLP evaluated there fails)
            return 0.5 * lib.tanh(0.5 * slope * (qd + shift)) + 0.5 \
                - 1 / (1 + np.exp(-slope * shift))
        raise IdentificationError(f"the {self.name} law has no column of its own")

    def term(self, joint: int) -> str:
        """The column's name in a model's equation of joint `joint` (1-based)."""
        return f"{self.name}{joint}"

    def describe(self) -> str:
        if self.name == "stribeck":
            return f"stribeck, v_s = {self.shape[0]:g} rad/s"
        if self.name == "sigmoid":
            return f"sigmoid (Gaz et al.), slope {self.shape[0]:g} s/rad, shift {self.shape[1]:g} rad/s"
        return self.name

    def to_dict(self) -> dict:
        """{"law", "shape"} (read back) and a "description" of both for people."""
        return {"law": self.name, "shape": list(self.shape), "description": DESCRIPTIONS[self.name]}

    @classmethod
    def from_dict(cls, payload) -> FrictionLaw:
        if not isinstance(payload, dict) or not isinstance(payload.get("shape", []), list):
            raise IdentificationError("malformed model: a friction entry must be "
                                      "{'law': name, 'shape': [numbers]}")
        try:
            shape = tuple(float(x) for x in payload.get("shape", []))
        except (TypeError, ValueError):
            raise IdentificationError("malformed model: friction shape must be numbers") from None
        return cls(str(payload.get("law")), shape)


def candidate_laws() -> list[FrictionLaw]:
    """Every law and shape the choice is made among (viscous, then viscous-coulomb first)."""
    return ([FrictionLaw("viscous"), FrictionLaw()] + [FrictionLaw("stribeck", (v,)) for v in STRIBECK_SPEEDS]
            + [FrictionLaw("sigmoid", (s, d)) for s in SIGMOID_SLOPES for d in SIGMOID_SHIFTS])


def law_design(law: FrictionLaw, qd: np.ndarray, coulomb: np.ndarray) -> np.ndarray:
    """(n, k) columns of one joint's friction under `law`: viscous, [Coulomb], [own column],
    offset (+1) - every coefficient but the offset's non-negative."""
    cols = [qd] + ([coulomb] if law.keeps_coulomb else [])
    if law.has_column:
        cols.append(law.column(qd))
    return np.column_stack(cols + [np.ones_like(qd)])


def choose_law(residual: np.ndarray, qd: np.ndarray, coulomb: np.ndarray, folds: int = 5,
               margin: float = 0.05, runs=None) -> tuple[FrictionLaw, list[tuple[FrictionLaw, float]]]:
    """The law whose fit of one joint's friction residual (the torque minus the rigid body's,
    n samples) predicts it best in blocked cross-validation (`folds` contiguous blocks, each
    predicted from the others), the simpler preferred: viscous-coulomb must beat viscous,
    and a law with a column of its own the one of those chosen, by `margin` (relative mean
    square). Also every candidate's validation error. runs: (n,) labels of several runs:
    each run is a fold instead (leave one run out), the residual and the design centred
    within each run (every run its own offset: the run left out is scored after its mean
    residual is removed)."""
    from scipy.optimize import nnls

    from identification.regression.base import within_runs

    if runs is None:
        blocks = np.array_split(np.arange(len(residual)), folds)
    else:
        labels = np.asarray(runs)
        blocks = [np.flatnonzero(labels == r) for r in np.unique(labels)]
        residual = within_runs(residual, labels)
    scored = []
    for law in candidate_laws():
        x = law_design(law, qd, coulomb)
        if runs is None:
            x = np.column_stack([x, -x[:, -1]])  # the offset free: +1 and -1, both >= 0
        else:
            x = within_runs(x[:, :-1], labels)  # an offset per run: centred away
        error = 0.0
        for block in blocks:
            train = np.ones(len(residual), bool)
            train[block] = False
            coef, _ = nnls(x[train], residual[train], maxiter=50 * x.shape[1])
            error += float(np.sum((x[block] @ coef - residual[block]) ** 2))
        scored.append((law, error / len(residual)))
    simple = scored[1] if scored[1][1] < (1 - margin) * scored[0][1] else scored[0]
    best = min(scored[2:], key=lambda s: s[1])
    return (best if best[1] < (1 - margin) * simple[1] else simple)[0], scored
