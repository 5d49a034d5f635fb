"""Physically consistent identification (identification.physical, .consistent, .friction):
the pseudo-inertia of a rigid body is positive semidefinite (a point mass, a negative mass, a
triangle inequality broken), the fit keeps every body consistent, recovers the truth from
noise-free MuJoCo data, pulls toward a nominal model only as far as validation inside the
training data allows, folds into the base atoms without changing a prediction, and chooses
the friction law the data were made with."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from harness.data.generate import generate
from harness.identify.scoring import perturbed_nominal, sines_motion
from harness.robots.arm import Arm
from identification.ellipsoids import Ellipsoid, enclosing, holding, inside
from identification.friction import FrictionLaw, choose_law
from identification.identify import identify
from identification.metrics import rel_error
from identification.model import model_from_dict, model_to_dict
from identification.physical import fit_physical, min_pseudo_eigenvalues, pseudo_inertia
from identification.regression.consistent import ConsistentRegressor
from tests.helpers import fail_clarabel


def test_pseudo_inertia_says_which_bodies_are_physical():
    point = pin.Inertia(2.0, np.array([0.1, 0.0, 0.0]), np.zeros((3, 3)))  # a point mass
    rod = pin.Inertia(1.0, np.zeros(3), np.diag([0.1, 0.1, 1e-6]))
    assert min_pseudo_eigenvalues(point.toDynamicParameters()) >= -1e-12
    assert min_pseudo_eigenvalues(rod.toDynamicParameters()) >= -1e-12
    negative = rod.toDynamicParameters() * np.r_[-1.0, np.ones(9)]  # negative mass
    broken = pin.Inertia(1.0, np.zeros(3), np.diag([0.1, 0.1, 0.5])).toDynamicParameters()
    assert min_pseudo_eigenvalues(negative) < 0 and min_pseudo_eigenvalues(broken) < 0


@pytest.fixture(scope="module")
def lynx():
    library = Arm.of("lynxmotion").library
    return library, Arm.of("lynxmotion").nominal, sines_motion(Arm.of("lynxmotion"), 600, 9)


def test_noise_free_truth_recovered_on_another_motion(lynx):
    """MuJoCo's torque (armature and damping included) is in the atoms' span: with or without
    the true nominal, the fit predicts a motion of another family to 1e-3."""
    library, base, judge = lynx
    data = generate(Arm.of("lynxmotion"), 1500, 0.0, 3, "inverse")
    atoms = library.evaluate_every(data.q, data.qd, data.qdd)
    judged = library.evaluate_every(judge.q, judge.qd, judge.qdd)
    for nominal in (base.atom_parameters(), np.zeros(39)):
        fit = fit_physical(atoms, data.qd, data.tau, nominal, choose_friction=False)
        assert fit.consistent and np.all(fit.min_eigenvalues >= -1e-8)
        # armature and friction exactly >= 0, not to the solver's tolerance (an exported
        # <dynamics friction> of -1e-11 is refused by Pinocchio)
        assert np.all(fit.params[30:] >= 0.0) and np.all(fit.law_coefficients >= 0.0)
        pred = fit.torque(judged, judge.qd, offsets=False)
        assert np.max(rel_error(pred, judge.tau_clean)) <= 1e-3


def test_a_wrong_nominal_is_not_followed_where_the_data_speak(lynx):
    """5 % noise, a nominal 30 % heavy: the fit predicts an unseen motion far better than the
    nominal model itself, and its folded model predicts exactly what the fit does."""
    library, base, judge = lynx
    data = generate(Arm.of("lynxmotion"), 1500, 0.05, 3, "inverse")
    wrong = base.atom_parameters() * 1.3
    result = identify(data.q, data.qd, data.qdd, data.tau, library, 0.25, data.tau_clean,
                      ConsistentRegressor(wrong))
    assert result.physical["consistent"] and result.physical["prior"] == "nominal"
    judged = library.evaluate_every(judge.q, judge.qd, judge.qdd)
    ours = result.model.torque(judge.q, judge.qd, judge.qdd)
    assert np.all(rel_error(ours, judge.tau_clean)
                  < 0.2 * rel_error(judged @ wrong, judge.tau_clean))
    params = np.r_[result.physical["standard_parameters"],
                   *result.physical["joint_parameters"].values()]
    np.testing.assert_allclose(ours, judged @ params + result.model.law_coefficients
                               * np.column_stack([law.column(judge.qd[:, j]) if law.has_column
                                                  else np.zeros(len(judge.q))
                                                  for j, law in enumerate(result.model.laws)]),
                               atol=1e-9 * np.abs(ours).max())


def test_a_perturbed_nominal_stays_physical_and_differs(lynx):
    _, base, _ = lynx
    nominal = perturbed_nominal(base, 4)
    assert np.all(min_pseudo_eigenvalues(nominal[:30]) >= 0)
    ratio = nominal[:30:10] / base.atom_parameters()[:30:10]  # masses
    assert np.all((ratio >= 0.7) & (ratio <= 1.3)) and np.ptp(ratio) > 0.01


@pytest.mark.parametrize("law", [FrictionLaw("sigmoid", (30.0, 0.03)), FrictionLaw("stribeck", (0.03,)),
                                 FrictionLaw(), FrictionLaw("viscous")])
def test_the_law_the_data_were_made_with_is_chosen(law):
    rng = np.random.default_rng(5)
    t = np.arange(4000) / 100
    qd = 0.6 * np.sin(0.7 * t) + 0.3 * np.sin(1.9 * t + 1)
    coulomb = qd / np.sqrt(qd**2 + 1e-6)
    torque = 0.4 * qd + 0.2 + (0.5 * coulomb if law == FrictionLaw() else 0.0)
    if law.has_column:
        torque = torque + 0.5 * law.column(qd) + (0.3 * coulomb if law.keeps_coulomb else 0)
    chosen, scored = choose_law(torque + 0.01 * rng.normal(size=len(t)), qd, coulomb)
    assert chosen == law, [(s[0].describe(), round(s[1], 6)) for s in scored[:4]]


def test_friction_law_columns_agree_in_casadi_and_round_trip():
    qd = np.linspace(-1, 1, 41)
    x = ca.SX.sym("qd")
    for law in (FrictionLaw("sigmoid", (10.0, -0.03)), FrictionLaw("stribeck", (0.1,))):
        f = ca.Function("f", [x], [law.column(x, ca)])
        np.testing.assert_allclose(np.asarray(f(qd)).ravel(), law.column(qd), atol=1e-12)
        assert FrictionLaw.from_dict(law.to_dict()) == law


def test_consistent_model_reads_back_from_model_json(lynx):
    library, base, judge = lynx
    data = generate(Arm.of("lynxmotion"), 1500, 0.02, 5, "inverse")
    model = identify(data.q, data.qd, data.qdd, data.tau, library, 0.25, data.tau_clean,
                     ConsistentRegressor(perturbed_nominal(base, 2))).model
    back = model_from_dict(model_to_dict(model), lambda: library)
    np.testing.assert_allclose(back.torque(judge.q, judge.qd, judge.qdd),
                               model.torque(judge.q, judge.qd, judge.qdd), rtol=1e-12, atol=1e-12)
    assert back.laws == model.laws and back.method == "consistent"
    # each joint's equation names its viscous atom in its own unit (a viscous law's name is
    # also that atom's: it is no column of the law's), and a law's own column in N m
    for j, (equation, law) in enumerate(zip(model.equations(), model.laws, strict=True)):
        kept = any(name == f"viscous{j + 1}" for name, _ in model.joint_terms(j))
        assert (f"N m s/rad * Y{j + 1}[viscous{j + 1}]" in equation) == kept
        assert (f"N m * {law.term(j + 1)}[" in equation) == law.has_column


def test_a_fallback_to_scs_is_warned_and_recorded(lynx, monkeypatch):
    """When Clarabel fails, the fit says so (a warning the CLI prints) and records the solver
    it took; a normal fit records Clarabel."""

    library, _, _ = lynx
    data = generate(Arm.of("lynxmotion"), 600, 0.01, 3, "inverse")
    atoms = library.evaluate_every(data.q, data.qd, data.qdd)
    fit = fit_physical(atoms, data.qd, data.tau, np.zeros(39), lambdas=(1e-6,),
                       choose_friction=False)
    assert fit.validation["solver"] == "CLARABEL"
    fail_clarabel(monkeypatch)
    with pytest.warns(RuntimeWarning, match="solved by SCS"):
        fit = fit_physical(atoms, data.qd, data.tau, np.zeros(39), lambdas=(1e-6,),
                           choose_friction=False)
    assert fit.validation["solver"] == "SCS"


def test_the_solver_is_in_the_metrics(lynx):
    """MODEL.json's metrics.physical names the solver the consistent fit took (issue #45)."""
    library, _, _ = lynx
    data = generate(Arm.of("lynxmotion"), 600, 0.01, 3, "inverse")
    result = identify(data.q, data.qd, data.qdd, data.tau, library, 0.25, data.tau_clean,
                      ConsistentRegressor(None, choose_friction=False))
    assert result.metrics()["physical"]["solver"] == "CLARABEL"


def test_the_ellipsoid_row_keeps_a_body_inside(lynx):
    """A sphere that excludes body 2's true centre of mass: the fit without the bound puts the
    mass outside (tr(J Q) < 0), the fit with it inside (tr(J Q) >= 0), still consistent."""
    library, base, _ = lynx
    nominal = base.atom_parameters()
    data = generate(Arm.of("lynxmotion"), 800, 0.0, 3, "inverse")
    atoms = library.evaluate_every(data.q, data.qd, data.qdd)
    c = nominal[11:14] / nominal[10]  # body 2's centre of mass
    bound = Ellipsoid(c + 0.5 * np.linalg.norm(c) + 0.02, np.full(3, 0.3 * np.linalg.norm(c) + 0.01),
                      np.eye(3))

    def held(fit):
        return inside(np.array(pseudo_inertia(fit.params[10:20])), bound)

    free = fit_physical(atoms, data.qd, data.tau, nominal, choose_friction=False)
    bounded = fit_physical(atoms, data.qd, data.tau, nominal, choose_friction=False,
                           bounds=[None, bound.matrix, None])
    assert held(free) < 0 and held(bounded) >= -1e-8 and bounded.consistent


@pytest.fixture(scope="module")
def excluded(lynx):
    """Noise-free data, and a sphere excluding body 2's true centre of mass (the flat fit's
    body 2 without a bound is the truth: outside)."""
    nominal = lynx[1].atom_parameters()
    c = nominal[11:14] / nominal[10]
    bound = Ellipsoid(c + 0.5 * np.linalg.norm(c) + 0.02, np.full(3, 0.3 * np.linalg.norm(c) + 0.01),
                      np.eye(3), "test")
    return generate(Arm.of("lynxmotion"), 800, 0.0, 3, "inverse"), bound


def _bounded_fit(lynx, excluded):
    data, bound = excluded
    regressor = ConsistentRegressor(None, choose_friction=False, ellipsoids=(None, bound, None))
    fit = regressor.fit(lynx[0], data.q, data.qd, data.qdd, data.tau)
    body = fit.physical["standard_parameters"][10:20]
    return fit.physical, inside(np.array(pseudo_inertia(np.asarray(body))), bound)


def test_the_regressors_ellipsoids_keep_a_body_inside_and_say_so(lynx, excluded):
    """ConsistentRegressor's ellipsoids reach the LMI: body 2 inside its sphere, plausible
    (#56 item 6: the regressor fitting without them passed every fast test)."""
    physical, held = _bounded_fit(lynx, excluded)
    assert held >= -1e-8 and physical["plausible"] == [True, True, True]
    assert physical["ellipsoids"][1]["source"] == "test"


def test_the_plausible_flag_says_when_a_body_is_outside(lynx, excluded, monkeypatch):
    """The same fit with the LMI's ellipsoid rows dropped: body 2 leaves its sphere and the
    flag says so (#56 item 6: a flag forced to True passed)."""
    from identification.regression import consistent

    unbounded = consistent.fit_physical
    monkeypatch.setattr(consistent, "fit_physical",
                        lambda *args, bounds=None, **kwargs: unbounded(*args, **kwargs))
    physical, held = _bounded_fit(lynx, excluded)
    assert held < 0 and physical["plausible"] == [True, False, True]


def test_a_point_mass_is_inside_exactly_when_its_point_is():
    """tr(J Q) of a point mass m at p is m (1 - (p - c)^T S^-2 (p - c)): the closed form."""
    rng = np.random.default_rng(5)
    bound = Ellipsoid(rng.normal(size=3), rng.uniform(0.1, 1.0, 3),
                      np.linalg.qr(rng.normal(size=(3, 3)))[0])
    for _ in range(20):
        p, m = bound.centre + rng.normal(size=3), rng.uniform(0.1, 5.0)
        pseudo = m * np.outer(np.append(p, 1.0), np.append(p, 1.0))  # [[p p^T, p], [p^T, 1]] m
        u = bound.axes.T @ (p - bound.centre) / bound.semi_axes
        assert inside(pseudo, bound) == pytest.approx(m * (1 - u @ u), rel=1e-9, abs=1e-12)


def test_the_enclosing_ellipsoid_holds_every_point_and_is_smaller_than_the_boxs():
    """Every point inside; the volume below the ellipsoid circumscribing the points' box
    (semi-axes sqrt(3) x the half extents)."""
    rng = np.random.default_rng(6)
    points = rng.normal(size=(300, 3)) * [0.2, 0.05, 0.03] + [0.1, 0.0, 0.3]
    bound = enclosing(points)
    u = (points - bound.centre) @ bound.axes / bound.semi_axes
    assert np.linalg.norm(u, axis=1).max() <= 1 + 1e-9
    box = np.sqrt(3) * np.ptp(points, axis=0) / 2
    assert np.prod(bound.semi_axes) < np.prod(box)


def test_an_ellipsoid_grows_to_hold_the_nominal_body(lynx):
    nominal = lynx[1].atom_parameters()
    pseudo = np.array(pseudo_inertia(nominal[10:20]))
    tiny = Ellipsoid(np.zeros(3), np.full(3, 1e-3), np.eye(3), "test")
    grown = holding(tiny, pseudo)
    assert inside(pseudo, tiny) < 0 <= inside(pseudo, grown) and "grown" in grown.source


def test_the_entropic_prior_is_the_logdet_divergence_of_the_pseudo_inertias():
    """_prior_cost's entropic term at a body J against its nominal J0 equals, in closed form,
    tr(J0^-1 J) - log det J + log det J0 (the LogDet divergence plus 4), for random bodies."""
    import cvxpy as cp

    from identification.physical import _prior_cost

    rng = np.random.default_rng(7)
    for _ in range(5):
        bodies = []
        for _ in range(2):
            rotation = pin.Quaternion(rng.normal(size=4)).normalized().matrix()
            second = rng.uniform(0.005, 0.1, 3)  # a mass distribution's second moments
            inertia = rotation @ np.diag(second.sum() - second) @ rotation.T
            bodies.append(pin.Inertia(rng.uniform(0.5, 3.0), rng.normal(0, 0.1, 3),
                                      inertia).toDynamicParameters())
        nominal, body = np.r_[bodies[0], np.zeros(3)], np.r_[bodies[1], np.zeros(3)]
        x, y = cp.Parameter(13, value=body), cp.Parameter(13, value=np.zeros(13))
        value = _prior_cost(x, y, nominal, 1, "entropic").value
        j0, j = (np.array(pseudo_inertia(b), float) for b in (nominal, body))
        expected = np.trace(np.linalg.solve(j0, j)) - np.linalg.slogdet(j)[1] \
            + np.linalg.slogdet(j0)[1]
        assert value == pytest.approx(expected, rel=1e-9)
