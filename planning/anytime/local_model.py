"""The anytime SQP's local model of the elastic planning NLP (planning.formulation.nlp, elastic=True):
one function of (x, p, multipliers) giving the objective, its gradient, the rows, their
Jacobian in the polynomial coefficients and the coefficient block of the Lagrangian's
Hessian, the derivatives taken through the NLP's sites (each use of the torque model or of
the link distances differentiated in its own arguments, then chained)."""

from __future__ import annotations

import casadi as ca
import numpy as np

from planning.anytime.elastic_qp import Layout, slack_structure


def local_function(nlp, name: str) -> ca.Function:
    """(x, p, lam_g) -> one dense column: f, grad f, g, the rows' Jacobian in the
    coefficients (the slacks' columns are constants, checked here) and the coefficient block
    of the Lagrangian's Hessian (the slacks enter linearly), so that one
    call through a buffer (Function.buffer: no conversion of its outputs) gives everything."""
    lam = ca.SX.sym("lam", nlp.g.numel())
    layout = layout_of(nlp)
    coefficients = nlp.x[: layout.nc]
    rows, sign, _ = slack_structure(layout)  # the slacks' columns, which stay out
    expected = np.zeros((nlp.g.numel(), nlp.x.numel() - layout.nc))
    for column, (pair, value) in enumerate(zip(rows, sign, strict=True)):
        expected[pair[pair >= 0], column] = value
    slacks = ca.Function("slack_columns", [nlp.x, nlp.p], [ca.jacobian(nlp.g, nlp.x[layout.nc:])])
    rng = np.random.default_rng(0)  # numerically: called models leave symbolic zeros
    for _ in range(2):
        at = slacks(rng.uniform(-1, 1, nlp.x.numel()), rng.uniform(0.1, 1, nlp.p.numel()))
        if not np.array_equal(np.asarray(at), expected):
            raise ValueError("the NLP's slacks do not enter its rows as "
                             "elastic_qp.slack_structure")
    g, jacobian, hessian = through_sites(nlp, lam, coefficients)  # every NLP has torque sites
    hessian += ca.hessian(nlp.f, coefficients)[0]
    column = ca.vertcat(nlp.f, ca.gradient(nlp.f, nlp.x), g, ca.vec(jacobian.T),
                        ca.vec(hessian))  # row-major
    return ca.Function(name, [nlp.x, nlp.p, lam], [ca.densify(column)])


def through_sites(nlp, lam, coefficients) -> tuple[ca.SX, ca.SX, ca.SX]:
    """The rows g, their Jacobian in the coefficients and the coefficient block of the
    Hessian of lam'g, by the chain rule through the NLP's sites (planning.formulation.nlp.Site): the
    lifted rows are cheap expressions of the coefficients and the sites' outputs y, and each
    site is differentiated in its own arguments by one call of its derivative function (value,
    Jacobian, Hessian of seed'output), the seed being d(lam'g)/dy. CasADi's AD through the
    whole rows takes one forward-over-adjoint sweep of every site per coefficient instead
    (18 on the UR5, where a pose's distances vary in 6 joint angles): several times slower
    (docs/realtime.md, 'planning.anytime.local_model'). The sites' arguments
    must be affine in the coefficients and the lifted rows linear in y (both checked)."""
    y = ca.vertcat(*(site.output for site in nlp.sites))
    lagrangian = ca.dot(lam, nlp.lifted_g)
    seeds = ca.gradient(lagrangian, y)
    if ca.depends_on(seeds, y):
        raise ValueError("the NLP's lifted rows are not linear in its sites' outputs")
    derivatives: dict = {}
    values, through, curvature, at = [], [], ca.SX(coefficients.numel(), coefficients.numel()), 0
    for site in nlp.sites:
        varying = tuple(ca.depends_on(arg, coefficients) for arg in site.args)
        if (site.kind, varying) not in derivatives:
            derivatives[site.kind, varying] = _site_derivatives(site, varying)
        basis = ca.jacobian(ca.vertcat(*(a for a, v in zip(site.args, varying, strict=True) if v)),
                            coefficients)
        if ca.depends_on(basis, coefficients):
            raise ValueError(f"a {site.kind} site's arguments are not affine in the "
                             "coefficients")
        count = site.output.numel()
        value, jacobian, hessian = derivatives[site.kind, varying](*site.args,
                                                                   seeds[at:at + count])
        at += count
        values.append(value)
        through.append(jacobian @ basis)
        curvature += basis.T @ hessian @ basis
    dy = ca.vertcat(*through)  # the sites' outputs' Jacobian in the coefficients
    outer, _ = ca.hessian(lagrangian, ca.vertcat(coefficients, y))
    chain = ca.vertcat(ca.SX.eye(coefficients.numel()), dy)
    hessian = chain.T @ outer @ chain + curvature
    jacobian = ca.jacobian(nlp.lifted_g, coefficients) + ca.jacobian(nlp.lifted_g, y) @ dy
    value = ca.vertcat(*values)
    return tuple(ca.substitute(part, y, value) for part in (nlp.lifted_g, jacobian, hessian))


def _site_derivatives(site, varying: tuple[bool, ...]) -> ca.Function:
    """(site inputs, seed) -> the site's output, its Jacobian and the Hessian of seed'output
    in the inputs that vary (an SX function of its own: called, not copied, at every site)."""
    z = ca.vertcat(*(i for i, v in zip(site.inputs, varying, strict=True) if v))
    seed = ca.SX.sym("seed", site.expression.numel())
    hessian, _ = ca.hessian(ca.dot(seed, site.expression), z)
    return ca.Function(f"{site.kind}_derivatives", [*site.inputs, seed],
                       [site.expression, ca.jacobian(site.expression, z), hessian],
                       {"never_inline": True})


def layout_of(nlp) -> Layout:
    nc = nlp.x.numel() - nlp.slack.numel() - nlp.elastic.numel()
    ne = nlp.slack.numel()
    return Layout(nc, slice(nc, nc + ne), slice(nc + ne, nlp.x.numel()), *nlp.epigraph,
                  nlp.clearance_rows)
