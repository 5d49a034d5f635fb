"""A generic polynomial x trig library for any dof, for a structure nobody knows."""

from __future__ import annotations

from itertools import combinations_with_replacement, product

from identification.library.base import Library
from identification.library.features import Feature, Trig


def angle_sums(dof: int, max_coeff: int = 1, joints: tuple[int, ...] | None = None):
    """Integer combinations c . q with |c_i| <= max_coeff, first non-zero c positive."""
    joints = tuple(range(dof)) if joints is None else joints
    out = []
    for cs in product(range(-max_coeff, max_coeff + 1), repeat=len(joints)):
        nz = [c for c in cs if c]
        if nz and nz[0] > 0:
            full = [0] * dof
            for j, c in zip(joints, cs, strict=True):
                full[j] = c
            out.append(tuple(full))
    return out


def trig_monomials(angle: tuple[int, ...], order: int) -> list[tuple[Trig, ...]]:
    """sin^a cos^b of one angle, b in {0, 1} (cos^2 = 1 - sin^2), 1 <= a + b <= order."""
    out = []
    for a in range(order + 1):
        for b in (0, 1):
            if 1 <= a + b <= order:
                factors = ([Trig("sin", angle, a)] if a else []) + ([Trig("cos", angle)] if b else [])
                out.append(tuple(factors))
    return out


def mechanical_motions(dof: int, positions: bool = True) -> list[tuple[tuple[str, int], ...]]:
    """1, q_i (optional), qd_i, qdd_i and qd_i qd_j: the motion factors of a Lagrangian
    system whose kinetic energy is quadratic in qd (plus springs if positions)."""
    out: list[tuple[tuple[str, int], ...]] = [()]
    out += [(("q", j),) for j in range(dof)] if positions else []
    out += [(("qd", j),) for j in range(dof)] + [(("qdd", j),) for j in range(dof)]
    out += [(("qd", i), ("qd", j)) for i, j in combinations_with_replacement(range(dof), 2)]
    return out


def generic_library(dof: int, order: int = 1, max_coeff: int = 1,
                    trig_joints: tuple[int, ...] | None = None) -> Library:
    """Polynomial x trig library for a structure nobody knows.

    Every mechanical motion factor (see `mechanical_motions`; q_i only when
    order = 0, a polynomial library) times 1 and every
    trig monomial of order <= `order` of every joint-angle sum with coefficients
    |c| <= max_coeff over `trig_joints` (default all joints).
    """
    trigs: list[tuple[Trig, ...]] = [()]
    for angle in angle_sums(dof, max_coeff, trig_joints) if order else []:
        trigs += trig_monomials(angle, order)
    # positions only without trig terms: q_i next to sin(q_i) is nearly collinear
    feats = [Feature(m, t) for m in mechanical_motions(dof, positions=order == 0) for t in trigs
             if m or t]  # the constant is the regression's intercept, not a feature
    return Library(f"generic-{dof}dof-o{order}c{max_coeff}", dof, tuple(feats))
