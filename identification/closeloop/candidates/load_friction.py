"""Dry friction that grows with the load a joint carries, as candidates of the measured loop
(identification.closeloop.selection.runs).

A load on the flange presses every gear downstream of it harder: a joint's dry friction is
F_c + mu |L_j| (Hamon, Gautier & Garrec, "Dynamic identification of robots with a dry
friction model depending on load and velocity", IROS 2010), L_j the torque the joint
transmits. The term is bilinear, the load L depending on the very payload it is fitted
beside, so, as Hamon et al. do, the load is the model's: during selection the declared
model plus the payload candidate fitted on the training runs (the load as far as the data
know it before anything is named), and once effects are named the closed model without its
load friction, alternated with the joint fit until the coefficients settle (REFITS passes).
The column of joint j is |L_j| sat((qd_j + lead qdd_j) / eps), mu in N m per N m; its shape
(lead, eps) is fitted by variable projection (identification.closeloop.selection.one_log.fit_shape)
on the residual the payload candidate leaves: on the residual itself a load's torque, far
larger, sets the shape (the UR5 payload case: eps at its 2 rad/s bound, a viscous term).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from identification.closeloop.candidates.effects import EffectTerm, effect_torque
from identification.closeloop.candidates.payload import com_agreement

EFFECT = "load_friction"
REFITS = 3  # passes of (load from the model, joint fit) once load friction is named
CANDIDATE_PASSES = 2  # passes of (payload candidate beside the friction, friction under it)


def load_candidates(project, residual: np.ndarray, load: np.ndarray, states) -> tuple[list, list]:
    """Unit `load_friction` terms on every joint and their (n, dof) columns under the load
    (n, dof) N m, each one's shape fitted on residual (n, dof) N m (project: the measured
    loop's projection off the runs' offsets)."""
    from identification.closeloop.selection.one_log import fit_shape

    dof = load.shape[1]
    out, cols = [], []
    for j in range(1, dof + 1):
        lead, eps = fit_shape(EFFECT, j, project, project(residual), states, load)
        term = EffectTerm(EFFECT, j, 1.0, lead=lead, eps=eps)
        out.append(term)
        cols.append(effect_torque((term,), *states, load=load))
    return out, cols


def with_payload(project, target: np.ndarray, declared: np.ndarray, states, payload_fit: Callable,
                 ) -> tuple[list, list, tuple | None]:
    """The load friction candidates and the payload candidate, each fitted knowing the other:
    the payload candidate beside every joint's load friction column, the columns under the
    declared torque declared (n, dof) plus that payload's, their shapes on the residual it
    leaves (CANDIDATE_PASSES passes from the payload fitted alone). payload_fit(beside
    (n, dof, k) or None) -> (unit column, parameters per kg, parameters) or None."""
    def under(payload) -> tuple[list, list]:
        carried = 0.0 if payload is None else payload[0] * payload[2][0]
        return load_candidates(project, target - carried, declared + carried, states)

    payload = payload_fit(None)
    for _ in range(0 if payload is None else CANDIDATE_PASSES):
        payload = payload_fit(np.stack(under(payload)[1], axis=2))
    return *under(payload), payload


def refit_under_load(fit: Callable, model_load: Callable, terms: list[EffectTerm],
                     cols: np.ndarray, chosen: list[int], states) -> tuple:
    """The joint fit with the named load friction's columns recomputed under the load of the
    model fitted (alternation, REFITS passes): fit(cols) -> (coef_base, coef, extra...) in
    chosen order, model_load(that output) -> (n, dof) the closed model's torque without
    its load friction. Returns fit's last output and the columns it was made on."""
    out = fit(cols)
    named = [i for i in chosen if terms[i].effect == EFFECT]
    if not named:
        return out, cols
    cols = cols.copy()
    for _ in range(REFITS):
        load = model_load(out)
        for i in named:
            cols[:, :, i] = effect_torque((terms[i],), *states, load=load)
        out = fit(cols)
    return out, cols


def spread_with_and_without(detail: dict, fit_spread: Callable, others: list[int],
                            terms: list[EffectTerm], within: float) -> dict:
    """A named payload's per-run detail (identification.closeloop.candidates.payload.named_payload) with
    what the runs' centres of mass do without the named load friction, and which reading the
    loop believes: fit_spread(effects) -> (mass, com, std) per run with those effects beside."""
    without = [i for i in others if terms[i].effect != EFFECT]
    if len(without) == len(others) or "com_agrees" not in detail:
        return detail
    mass, com, std = fit_spread(without)
    agrees = com_agreement(com, std, within)
    if detail["com_agrees"] and not agrees:
        note = ("the runs' centres of mass disagree without the load friction and agree with it:"
                " the disagreement was the friction's, not a load moved between runs")
    elif not detail["com_agrees"]:
        note = ("the runs' centres of mass disagree with the load friction named as without it:"
                " the load was likely moved between runs (or an effect the dictionary lacks)")
    else:
        note = "the runs' centres of mass agree with and without the load friction"
    return {**detail, "per_run_mass_without_load_friction": mass.tolist(),
            "per_run_com_without_load_friction": com.tolist(),
            "com_agrees_without_load_friction": agrees, "load_friction_note": note}


VIF_LIMIT = 10.0  # variance inflation past which two terms are not told apart (the usual 10)


def told_apart(detail: dict, mass: float, interval: float, payload: np.ndarray,
               friction: np.ndarray, project: Callable) -> dict:
    """A named payload's detail with whether the data tell it from the named load friction:
    the variance inflation of the payload's column (n, dof) by the friction's columns
    (n, dof, k), both weighted and with the runs' offsets projected out (project), 1 / (1 -
    R^2) of the one regressed on the others. Past VIF_LIMIT a load's torque and friction
    growing with it look alike on these data, the two trade, and the reading is the mass's
    95 % interval as a range, not a point (one real load read 2.38 and 2.17 kg on
    two runs this way)."""
    if friction.shape[2] == 0:
        return detail
    y, X = project(payload)[:, 0], project(friction)
    fitted = X @ np.linalg.lstsq(X, y, rcond=None)[0]
    share = float(fitted @ fitted / max(y @ y, 1e-300))  # R^2 (no mean: offsets projected out)
    inflation = 1.0 / max(1.0 - share, 1e-12)
    apart = inflation < VIF_LIMIT
    low, high = mass - interval, mass + interval
    note = (f"the payload is told apart from the load friction on these data (variance "
            f"inflation {inflation:.3g} < {VIF_LIMIT:g})" if apart else
            f"the payload and the load friction trade on these data (variance inflation "
            f"{inflation:.3g} >= {VIF_LIMIT:g}): the mass lies in [{low:.3g}, {high:.3g}] kg, "
            "not at a point")
    return {**detail, "variance_inflation": inflation, "told_apart": bool(apart),
            **({} if apart or not np.isfinite(interval) else {"mass_range_kg": [low, high]}),
            "mass_note": note}
