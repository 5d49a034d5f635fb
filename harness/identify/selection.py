"""What a sparse fit's selection did on one draw, against the fit's own noise-free terms.

The noise-free terms are those the same fit keeps on the draw's clean torque (the terms the
data need: the library spans the truth there). The selection's ceiling is weighted least
squares on exactly those terms, fitted on the noisy torque (per-joint offsets, each joint
weighed by its noise, identification.regression.coupled): no selection rule on this library
(held-out blocks, an information criterion, stability over resamples) can do better than
choosing them, so the fit's judge error over the ceiling's is what its selection cost.
Coupled fits only (one support over shared terms).
"""

from __future__ import annotations

import numpy as np

from identification.identify import identify
from identification.metrics import rel_error
from identification.regression.coupled import CoupledRegression
from identification.regression.weighted import weighted_lstsq


def kept_terms(result) -> list[str] | None:
    """Names of the terms a coupled identification kept (non-zero); None for another fit."""
    if result.method != "coupled" or result.basis is None or len(result.regressions) != 1:
        return None
    reg = result.regressions[0]
    names = result.basis.names
    return [names[k] for k in np.flatnonzero(reg.support_ & (reg.coef_ != 0))]


def ceiling_errors(basis, data, n_train: int, terms: list[str], judges) -> dict:
    """Judge errors (relative RMS per joint) of two-step weighted least squares on `terms`
    of basis (an AtomBasis or a KinematicLibrary) with per-joint offsets, fitted on the first
    n_train samples of data."""
    cols = [basis.names.index(t) for t in terms]
    design = basis.evaluate(data.q[:n_train], data.qd[:n_train], data.qdd[:n_train])
    tau = data.tau[:n_train]
    sigma = CoupledRegression().noise_sigma(design, tau, cols)
    coef = weighted_lstsq(design, tau, cols, sigma)[0]
    return {m.name: rel_error(basis.evaluate(m.q, m.qd, m.qdd)[:, :, cols] @ coef,
                              m.tau_clean).tolist() for m in judges}


def selection(fit, data, holdout: float, kept: list[str], judges) -> dict:
    """The draw's noise-free terms (fit identified on data.tau_clean), the terms the noisy
    fit dropped from them and kept beyond them (`kept`: kept_terms of the noisy fit), and the
    ceiling's judge errors (ceiling_errors on the noise-free terms)."""
    clean = identify(data.q, data.qd, data.qdd, data.tau_clean, fit.library, holdout,
                     data.tau_clean, fit.regressor(int(data.meta["seed"])))
    needed = kept_terms(clean)
    n = int(round(len(data.q) * (1 - holdout)))
    return {"needed": needed, "dropped": [t for t in needed if t not in kept],
            "spurious": [t for t in kept if t not in needed],
            "ceiling": ceiling_errors(clean.basis, data, n, needed, judges)}
