"""The identified parameters' 95 % intervals: the fit redone without each contiguous time
block of every training run (identification.intervals' delete-one-block jackknife), every
reading the summary prints read again on each fold.

Which readings, and why:
- a model on a robot's base atoms: each base atom's coefficient and each friction law's
  (base parameters are identifiable by construction: each is the sum of standard
  parameters KinematicLibrary.fold names, so it has one true value);
- a model on a feature library: each kept feature's coefficient per joint (the sparse
  selection is redone on each fold; a fold that drops the feature reads 0, so the interval
  carries the selection's doubt too);
- a physically consistent fit, also: each body's mass, centre of mass and inertia about it,
  each joint's armature, viscous and Coulomb coefficient. Standard parameters are not
  identifiable one by one: a reading whose gradient in them leaves the base parameters' row
  space is held by the prior and the constraints, not by the data, so it gets no interval
  (identifiable false), never one that says how firmly the prior holds it.
The consistent fit's folds keep the prior weight the whole fit chose (their friction laws
are chosen again, and a law's coefficient reads only on folds that chose the same law).
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from identification.bodies import JOINT_DYNAMICS, inertials
from identification.errors import IdentificationError
from identification.intervals import half_width, rule, time_blocks
from identification.kinematic_model import KinematicModel
from identification.library.kinematic import atom_unit

# the jackknife's blocks per run: fewer and longer than the loop's (identification.intervals
# BLOCKS = 8), as for the drive gains: a term the model lacks colours the residual over long
# times. On 10 development draws of the study parameter_intervals (seeds 100 + 2 d, none
# scored; a spring on q2 + q3 left out), 4 blocks covered the true base parameters in 84 %
# (Lynxmotion) and 96 % (UR5) of readings x draws, 8 blocks in 73-79 % and 94-96 %
PARAMETER_BLOCKS = 4
IDENTIFIABLE_TOL = 1e-6  # relative: a reading's gradient this far outside the base
# parameters' row space is not determined by the data
BODY_READINGS = (("mass", "kg", 1), ("com", "m", 3), ("inertia_at_com", "kg m^2", 9))


def readings(fit) -> dict[str, np.ndarray]:
    """The printed readings of one TorqueFit, by name: flat arrays (NaN where this fit has no
    value for a reading, e.g. a law it did not choose)."""
    model, out = fit.model, {}
    if isinstance(model, KinematicModel):
        out["coefficients"] = np.asarray(model.coefficients, float)
        laws = np.full(model.dof, np.nan)
        for j, _, c in model.law_terms():
            laws[j] = c
        out["laws"] = laws
    else:  # a feature model: per joint, its kept features' coefficients
        for j, joint in enumerate(model.joints):
            out[f"joint{j + 1}"] = dict(zip(joint.terms, joint.coefficients, strict=True))
    physical = fit.physical
    if physical and "standard_parameters" in physical:
        params = np.asarray(physical["standard_parameters"], float).reshape(-1, 10)
        out["bodies"] = np.array([body_readings(p) for p in params])
        out["joints_dynamics"] = np.array([physical["joint_parameters"][name]
                                           for name, _ in JOINT_DYNAMICS]).T
        out["law_names"] = [law.name for law in model.laws] if model.laws else []
    return out


def body_readings(p) -> np.ndarray:
    """(13,) one body's mass, centre of mass (3) and inertia about it (3x3, row-major) from
    its 10 standard parameters."""
    m, c, inertia = inertials(p)
    return np.concatenate([[m], c, inertia.ravel()])


def identifiable(fold: np.ndarray, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """((dof, 13), (dof, 3)) True where a body reading (body_readings) or a joint's armature,
    viscous or Coulomb coefficient is determined by the data: its gradient in the candidate
    atoms' coefficients (numerical, central) lies in fold's row space (fold: the base
    coefficients are fold @ x, (p, 13 dof); params: the fitted standard parameters, 10 a body
    first)."""
    _, s, vt = np.linalg.svd(fold, full_matrices=False)
    rows = vt[s > 1e-10 * s.max()]  # the row space, orthonormal
    dof = fold.shape[1] // 13
    out = np.zeros((dof, 13), bool)
    for b in range(dof):
        p = np.asarray(params[10 * b:10 * b + 10], float)
        step = 1e-6 * max(np.max(np.abs(p)), 1e-9)
        grad = np.zeros((13, fold.shape[1]))
        for k in range(10):
            dp = np.zeros(10)
            dp[k] = step
            grad[:, 10 * b + k] = (body_readings(p + dp) - body_readings(p - dp)) / (2 * step)
        outside = grad - (grad @ rows.T) @ rows
        norm = np.linalg.norm(grad, axis=1)
        out[b] = (norm > 0) & (np.linalg.norm(outside, axis=1) <= IDENTIFIABLE_TOL * norm)
    return out, _joint_identifiable(fold, rows, dof)


def _joint_identifiable(fold, rows, dof) -> np.ndarray:
    """(dof, 3) True where a joint's armature, viscous or Coulomb coefficient's unit vector
    lies in fold's row space (rows: an orthonormal basis of it)."""
    out = np.zeros((dof, 3), bool)
    for i in range(3):
        for j in range(dof):
            e = np.zeros(fold.shape[1])
            e[(10 + i) * dof + j] = 1.0
            out[j, i] = np.linalg.norm(e - (rows.T @ (rows @ e))) <= IDENTIFIABLE_TOL
    return out


def _fold_regressor(regressor, fit):
    """The regressor a fold refits with: a consistent fit at the prior weight it chose."""
    lam = fit.physical.get("lambda") if fit.physical else None
    if lam is not None and hasattr(regressor, "lambdas"):
        return replace(regressor, lambdas=(float(lam),))
    return regressor


def jackknife_readings(regressor, library, q, qd, qdd, tau, fit, runs=None,
                       blocks: int = PARAMETER_BLOCKS) -> list[dict]:
    """Each fold's readings: the regressor refitted on the samples (n, dof) without one of
    `blocks` contiguous blocks of every run (runs: (n,) labels; None: one run); a fold the
    regressor cannot fit is left out."""
    labels = np.zeros(len(q), int) if runs is None else np.asarray(runs)
    order = [np.flatnonzero(labels == r) for r in dict.fromkeys(labels.tolist())]
    every = np.arange(len(q))
    refit = _fold_regressor(regressor, fit)
    folds = []
    for block in time_blocks(order, blocks):
        rows = np.setdiff1d(every, block, assume_unique=True)
        kw = ({"runs": labels[rows]} if getattr(refit, "per_run_offsets", False)
              and len(np.unique(labels[rows])) > 1 else {})
        with warnings.catch_warnings():  # the whole fit's warnings were reported once
            warnings.simplefilter("ignore")
            try:
                folds.append(readings(refit.fit(library, q[rows], qd[rows], qdd[rows],
                                                tau[rows], **kw)))
            except (IdentificationError, ValueError, np.linalg.LinAlgError):
                continue
    return folds


def _half(values: list) -> np.ndarray:
    """The 95 % half-width of each column of the folds' values (B, ...), a column's
    non-finite folds left out (NaN under 3)."""
    values = np.array(values, float)
    flat = values.reshape(len(values), -1)
    return np.array([half_width(flat[:, [k]])[0] for k in range(flat.shape[1])]
                    ).reshape(values.shape[1:])


def parameter_intervals(regressor, library, q, qd, qdd, tau, fit, runs=None,
                        blocks: int = PARAMETER_BLOCKS) -> dict:
    """MODEL.json's parameter_intervals: each printed reading's value and 95 % half-width
    (identification.intervals), how they were computed, and, for a consistent fit's bodies,
    which readings the data determine."""
    folds = jackknife_readings(regressor, library, q, qd, qdd, tau, fit, runs, blocks)
    whole = readings(fit)
    out = {"rule": rule(blocks) + "; the fit redone on each fold" + (
        " at the prior weight the whole fit chose" if _fold_regressor(regressor, fit)
        is not regressor else ""), "level": 0.95, "folds": len(folds)}
    model = fit.model
    if isinstance(model, KinematicModel):
        half = _half([f["coefficients"] for f in folds]) if folds else np.full(len(library), np.nan)
        out["base_parameters"] = {
            name: {"value": float(v), "interval_95": float(h), "unit": atom_unit(name)}
            for name, v, h in zip(library.names, whole["coefficients"], half, strict=True)
            if v != 0}
        out["friction_laws"] = _laws(model, whole, folds)
    else:
        out["joints"] = [{name: {"value": float(v), "interval_95": float(_half(
            [[f[key].get(name, 0.0)] for f in folds])[0]) if folds else float("nan")}
            for name, v in whole[key].items()} for key in whole if key.startswith("joint")]
    if "bodies" in whole:
        out.update(_bodies(library, fit, whole, folds))
    return _nulls(out)


def _nulls(x):
    """x with every non-finite number null (JSON has no NaN: no interval is null)."""
    if isinstance(x, dict):
        return {k: _nulls(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_nulls(v) for v in x]
    return None if isinstance(x, float) and not np.isfinite(x) else x


def _laws(model, whole, folds) -> list[dict]:
    """Per joint whose law has a column of its own: its coefficient and half-width over the
    folds that chose the same law."""
    out = []
    for j, law, c in model.law_terms():
        same = [f["laws"][j] for f in folds
                if f.get("law_names", [law.name] * model.dof)[j] == law.name]
        out.append({"joint": j + 1, "term": law.term(j + 1), "value": c,
                    "interval_95": float(_half([[v] for v in same])[0]) if same else float("nan")})
    return out


def _bodies(library, fit, whole, folds) -> dict:
    """The bodies' and the joints' readings with half-widths where the data determine them."""
    params = np.asarray(fit.physical["standard_parameters"], float)
    body_ok, joint_ok = identifiable(library.fold, params)
    bodies_half = _half([f["bodies"] for f in folds]) if folds else np.full(whole["bodies"].shape, np.nan)
    joints_half = (_half([f["joints_dynamics"] for f in folds]) if folds
                   else np.full(whole["joints_dynamics"].shape, np.nan))
    bodies = []
    for b, (value, half, ok) in enumerate(zip(whole["bodies"], bodies_half, body_ok, strict=True)):
        entry, at = {"joint": b + 1}, 0
        for name, unit, size in BODY_READINGS:
            v, h, k = value[at:at + size], half[at:at + size], ok[at:at + size]
            at += size
            h = np.where(k, h, np.nan)
            shape = (3, 3) if size == 9 else ((3,) if size == 3 else ())
            entry[name] = {"value": _shaped(v, shape), "interval_95": _shaped(h, shape),
                           "identifiable": _shaped(k, shape), "unit": unit}
        bodies.append(entry)
    joints = [{"joint": j + 1, **{name: {"value": float(whole["joints_dynamics"][j, i]),
                                         "interval_95": float(joints_half[j, i]) if joint_ok[j, i]
                                         else float("nan"),
                                         "identifiable": bool(joint_ok[j, i]), "unit": unit}
                                  for i, (name, unit) in enumerate(JOINT_DYNAMICS)}}
              for j in range(len(joint_ok))]
    return {"bodies": bodies, "joints_dynamics": joints,
            "identifiable": "a reading is identifiable when its gradient in the standard "
                            "parameters lies in the base parameters' row space (the data "
                            "determine it); the others are held by the prior and the "
                            "constraints and get no interval"}


def _shaped(x: np.ndarray, shape: tuple):
    x = np.asarray(x)
    if x.dtype == bool:
        return bool(x[0]) if shape == () else x.reshape(shape).tolist()
    return float(x[0]) if shape == () else x.reshape(shape).tolist()
