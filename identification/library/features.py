"""Named features: products of joint-state monomials and trigonometric factors.

A feature is  prod_k m_k(q, qd, qdd)  *  prod_l trig_l(c_l . q)^p_l, e.g.
`qd1*qd2*sin(2*q2+q3)`. It evaluates on arrays of shape (n, dof) and, with the
same code path, on CasADi column vectors, so an identified model is one
expression for both the harness and the planner.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

STATES = ("q", "qd", "qdd")


@dataclass(frozen=True, order=True)
class Trig:
    """func(sum_i coeffs[i] * q_i) ** power, func in {'sin', 'cos'}."""

    func: str
    coeffs: tuple[int, ...]
    power: int = 1

    def angle_name(self) -> str:
        parts = []
        for i, c in enumerate(self.coeffs):
            if c == 0:
                continue
            sign = "-" if c < 0 else ("+" if parts else "")
            mag = "" if abs(c) == 1 else f"{abs(c)}*"
            parts.append(f"{sign}{mag}q{i + 1}")
        return "".join(parts) or "0"

    def name(self) -> str:
        base = f"{self.func}({self.angle_name()})"
        return base if self.power == 1 else f"{base}^{self.power}"


@dataclass(frozen=True, order=True)
class Feature:
    """A library column: motion monomial (state, joint) factors times trig factors.

    `motion` entries are (state, joint) with state in STATES and joint 0-based;
    repeated entries are powers. An empty feature is the constant 1.
    """

    motion: tuple[tuple[str, int], ...] = ()
    trig: tuple[Trig, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "motion", tuple(sorted(self.motion)))
        object.__setattr__(self, "trig", tuple(sorted(self.trig)))

    @property
    def name(self) -> str:
        counts: dict[str, int] = {}
        for s, j in self.motion:
            counts[f"{s}{j + 1}"] = counts.get(f"{s}{j + 1}", 0) + 1
        factors = [k if p == 1 else f"{k}^{p}" for k, p in counts.items()]
        factors += [t.name() for t in self.trig]
        return "*".join(factors) or "1"

    def evaluate(self, q, qd, qdd, lib=np):
        """Value of the feature. numpy: arrays (n, dof) -> (n,); casadi: vectors -> scalar.

        `lib` supplies sin/cos (numpy or casadi); indexing is [:, j] for numpy
        arrays and [j] for CasADi column vectors.
        """
        states = {"q": q, "qd": qd, "qdd": qdd}
        pick = (lambda x, j: x[:, j]) if lib is np else (lambda x, j: x[j])
        value = 1.0
        for state, j in self.motion:
            value = value * pick(states[state], j)
        for t in self.trig:
            angle = 0.0
            for j, c in enumerate(t.coeffs):
                if c:
                    angle = angle + c * pick(q, j)
            value = value * getattr(lib, t.func)(angle) ** t.power
        if lib is np and np.ndim(value) == 0:
            value = np.full(len(q), float(value))
        return value


def motion(*factors: str) -> tuple[tuple[str, int], ...]:
    """Parse 'qd1', 'qdd3' ... (1-based joints, as printed) into motion factors."""
    out = []
    for f in factors:
        state = f.rstrip("0123456789")
        if state not in STATES or state == f:
            raise ValueError(f"bad motion factor {f!r}")
        out.append((state, int(f[len(state):]) - 1))
    return tuple(out)


_ANGLE_TERM = re.compile(r"([+-]?)(\d*)\*?q(\d+)")
_TRIG = re.compile(r"^(sin|cos)\(([^()]*)\)(?:\^(\d+))?$")
MAX_POWER = 8  # no torque term of an arm has a higher power; more is a corrupt file
MAX_MULTIPLE = 16  # of a joint angle inside sin/cos
_MOTION = re.compile(r"^(qdd|qd|q)(\d+)(?:\^(\d+))?$")


def _split_factors(name: str) -> list[str]:
    """Split at '*' outside parentheses."""
    parts, depth, start = [], 0, 0
    for k, ch in enumerate(name):
        depth += {"(": 1, ")": -1}.get(ch, 0)
        if ch == "*" and depth == 0:
            parts.append(name[start:k])
            start = k + 1
    return parts + [name[start:]]


def parse_feature(name: str, dof: int) -> Feature:
    """The Feature printed as `name` (inverse of Feature.name), e.g. 'qd1^2*sin(2*q2+q3)'."""
    if name.strip() == "1":
        return Feature()
    motions: list[tuple[str, int]] = []
    trigs: list[Trig] = []
    for factor in _split_factors(name.replace(" ", "")):
        m, t = _MOTION.match(factor), _TRIG.match(factor)
        if (m and int(m.group(3) or 1) > MAX_POWER) or (t and int(t.group(3) or 1) > MAX_POWER):
            raise ValueError(f"power above {MAX_POWER} in feature {name!r}")
        if m and 1 <= int(m.group(2)) <= dof:
            motions += [(m.group(1), int(m.group(2)) - 1)] * int(m.group(3) or 1)
        elif t:
            coeffs = [0] * dof
            angle = t.group(2)
            terms = list(_ANGLE_TERM.finditer(angle))
            if not terms or "".join(x.group(0) for x in terms) != angle:
                raise ValueError(f"cannot parse angle {angle!r} in feature {name!r}")
            for x in terms:
                j = int(x.group(3)) - 1
                if not 0 <= j < dof:
                    raise ValueError(f"joint q{j + 1} out of range in feature {name!r}")
                coeffs[j] += (-1 if x.group(1) == "-" else 1) * int(x.group(2) or 1)
                if abs(coeffs[j]) > MAX_MULTIPLE:
                    raise ValueError(f"multiple of q{j + 1} above {MAX_MULTIPLE} in {name!r}")
            trigs.append(Trig(t.group(1), tuple(coeffs), int(t.group(3) or 1)))
        else:
            raise ValueError(f"cannot parse factor {factor!r} in feature {name!r}")
    return Feature(tuple(motions), tuple(trigs))
