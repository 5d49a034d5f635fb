"""Library generation from prior knowledge (paper II.E), derived, not guessed.

Torque is the Euler-Lagrange operator applied to a Lagrangian, and a
Lagrangian is a linear combination of *atoms*: kinetic qd_i qd_j f(c . q) and
potential f(c . q), f in {1, cos, sin}. Which atoms occur is the prior
knowledge each simple structure teaches:

- 1-DOF pendulum: qd1^2; potential cos/sin q1.
- planar 2-DOF arm: qd_i qd_j x {1, cos, sin of the relative angle q2};
  potential cos/sin of the absolute angles q1, q1+q2.
- spatial 2-DOF arm (vertical then horizontal axis): qd1^2 x {1, cos 2q2,
  sin 2q2} (the link's inertia about the vertical axis), qd1 qd2 x cos/sin q2
  (products of inertia), qd2^2; potential cos/sin q2.

A 3-DOF arm is a spatial base carrying a planar chain, so its atoms compose
the two: the planar atoms on the chain, and the spatial atoms with the one
elevation angle replaced by every pair of link elevations (the base inertia
is quadratic in the links' horizontal reach, so cos^2 th becomes cos(th_a +/-
th_b)). `derive` then applies the Euler-Lagrange operator to the atoms; the
features it produces are the library. `symmetric_links=True` keeps only the
atoms of links whose centre of mass lies on the link axis with principal axes
along it (the paper's arm); False adds the sine companions a general inertia
tensor needs.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations_with_replacement

from identification.library.base import Library
from identification.library.features import Feature, Trig

_DERIVATIVE = {"cos": "sin", "sin": "cos"}


@dataclass(frozen=True)
class Atom:
    """One Lagrangian term: qd_i qd_j * f(coeffs . q) (kinetic) or f(coeffs . q) (potential)."""

    velocities: tuple[int, ...]  # () for potential, (i, j) for kinetic
    func: str | None = None  # None: the constant 1
    coeffs: tuple[int, ...] = ()

    def trig(self, func: str | None = None) -> tuple[Trig, ...]:
        f = func or self.func
        return () if f is None else (Trig(f, self.coeffs),)


    @property
    def name(self) -> str:
        """The atom as printed, e.g. 'qd1*qd2*cos(q3)' or 'sin(q2+q3)'."""
        return Feature(tuple(("qd", k) for k in self.velocities), self.trig()).name


@dataclass(frozen=True)
class Combination:
    """A fixed linear combination of atoms with one shared coefficient: sum_k w_k atom_k."""

    parts: tuple[tuple[Atom, float], ...]

    @property
    def name(self) -> str:
        """The combination as printed, e.g. '(0.5*qd1^2*cos(q3) + qd2^2*cos(q3) + ...)'."""
        body = " + ".join(a.name if w == 1 else f"{w:g}*{a.name}" for a, w in self.parts)
        return f"({body})"


def atom_torque(atom: Atom | Combination, joint: int) -> dict[Feature, float]:
    """Euler-Lagrange torque of an atom or a combination on `joint`, as {feature: factor}."""
    if isinstance(atom, Combination):
        out: dict[Feature, float] = {}
        for part, weight in atom.parts:
            for f, v in _atom_torque(part, joint).items():
                out[f] = out.get(f, 0.0) + weight * v
        return {f: v for f, v in out.items() if v != 0.0}
    return _atom_torque(atom, joint)


def _atom_torque(atom: Atom, joint: int) -> dict[Feature, float]:
    """d/dt dL/dqd_joint - dL/dq_joint for L = atom, as {feature: factor}.

    L = qd_i qd_j f(c.q):  dL/dqd_joint = (1 + [i == j]) qd_other f, whose time
    derivative is qdd_other f + qd_other f'(c.q) sum_k c_k qd_k; dL/dq_joint =
    c_joint qd_i qd_j f'. Potential L = f(c.q): torque -c_joint f'. f' of cos
    is -sin, of sin is cos.
    """
    out: dict[Feature, float] = {}

    def add(feature: Feature, value: float) -> None:
        out[feature] = out.get(feature, 0.0) + value

    sign = {"cos": -1.0, "sin": 1.0}.get(atom.func or "", 0.0)
    slope = atom.trig(_DERIVATIVE[atom.func]) if atom.func else ()
    if atom.velocities:
        i, j = atom.velocities
        if joint in (i, j):
            other, mult = (j if joint == i else i), (2.0 if i == j else 1.0)
            add(Feature((("qdd", other),), atom.trig()), mult)
            for k, c in enumerate(atom.coeffs):
                if c and sign:
                    add(Feature((("qd", other), ("qd", k)), slope), mult * c * sign)
        if sign and atom.coeffs[joint]:
            add(Feature((("qd", i), ("qd", j)), slope), -atom.coeffs[joint] * sign)
    elif sign and atom.coeffs[joint]:
        add(Feature((), slope), -atom.coeffs[joint] * sign)
    return {f: v for f, v in out.items() if v != 0.0}


def _euler_lagrange(atom: Atom | Combination, joint: int) -> set[Feature]:
    """Features of the atom's torque on `joint` (factors dropped)."""
    return set(atom_torque(atom, joint))


def derive(atoms: list[Atom], dof: int, name: str) -> tuple[Library, tuple[frozenset, ...]]:
    """The library spanned by the Euler-Lagrange torques of atoms, and each joint's features."""
    per_joint = tuple(frozenset().union(*(_euler_lagrange(a, m) for a in atoms))
                      for m in range(dof))
    features = sorted(frozenset().union(*per_joint), key=lambda f: f.name)
    return Library(name, dof, tuple(features), tuple(atoms)), per_joint


def _funcs(symmetric: bool) -> tuple[str, ...]:
    return ("cos",) if symmetric else ("cos", "sin")


def pendulum_atoms() -> list[Atom]:
    """1-DOF pendulum about a horizontal axis."""
    return [Atom((0, 0))] + [Atom((), f, (1,)) for f in ("cos", "sin")]


def planar_atoms(dof: int = 2, first: int = 0, total: int | None = None,
                 symmetric: bool = True) -> list[Atom]:
    """Planar chain of `dof` parallel joints starting at joint `first` of a `total`-joint arm."""
    total = total or dof
    chain = range(first, first + dof)

    def vec(joints):
        return tuple(1 if k in joints else 0 for k in range(total))

    atoms = []
    for i, j in combinations_with_replacement(chain, 2):
        atoms.append(Atom((i, j)))
        for a, b in combinations_with_replacement(chain, 2):  # relative angle of links a, b
            if a < b:
                atoms += [Atom((i, j), f, vec(range(a + 1, b + 1))) for f in _funcs(symmetric)]
    for link in chain:  # gravity: absolute angle of each link
        atoms += [Atom((), f, vec(range(first, link + 1))) for f in ("cos", "sin")]
    return atoms


def absolute_chain_atoms(dof: int = 2, symmetric: bool = False) -> list[Atom]:
    """Planar chain in absolute link angles (a double pendulum's theta_i): kinetic
    qd_i qd_j x {1, f(q_a - q_b)} for every link pair a < b, potential cos/sin q_i."""
    def diff(a, b):
        return tuple(1 if k == a else -1 if k == b else 0 for k in range(dof))

    pairs = [(a, b) for a in range(dof) for b in range(a + 1, dof)]
    atoms = []
    for i, j in combinations_with_replacement(range(dof), 2):
        atoms.append(Atom((i, j)))
        atoms += [Atom((i, j), f, diff(a, b)) for a, b in pairs for f in _funcs(symmetric)]
    unit = [tuple(int(k == i) for k in range(dof)) for i in range(dof)]
    return atoms + [Atom((), f, u) for u in unit for f in ("cos", "sin")]


def spatial_atoms(total: int = 2, symmetric: bool = True) -> list[Atom]:
    """Vertical joint 0 carrying a planar chain of joints 1..total-1 (elevation angles)."""
    elevations = [tuple(1 if 1 <= k <= link else 0 for k in range(total))
                  for link in range(1, total)]
    atoms = [Atom((0, 0))]
    for a, b in combinations_with_replacement(range(len(elevations)), 2):
        plus = tuple(x + y for x, y in zip(elevations[a], elevations[b], strict=True))
        minus = tuple(y - x for x, y in zip(elevations[a], elevations[b], strict=True))
        for vec in (plus, minus):
            if any(vec):
                atoms += [Atom((0, 0), f, vec) for f in _funcs(symmetric)]
    if not symmetric:  # products of inertia couple the base to the chain
        atoms += [Atom((0, k), f, e) for k in range(1, total) for e in elevations
                  for f in ("cos", "sin")]
    return atoms


def _elevations(total: int) -> list[tuple[int, ...]]:
    """Absolute elevation th_a of each chain link a = 1..total-1 as angle coefficients."""
    return [tuple(1 if 1 <= k <= link else 0 for k in range(total)) for link in range(1, total)]


def link_pair_atoms(total: int, a: int, b: int, func: str) -> Combination:
    """Rigid link pair a < b (chain links, 0-based) of a vertical-base arm: the base's reach
    product qd1^2 cos th_a * {cos, sin} th_b plus the chain's w_a w_b f(th_b - th_a)."""
    ea, eb = _elevations(total)[a], _elevations(total)[b]
    plus = tuple(x + y for x, y in zip(ea, eb, strict=True))
    minus = tuple(y - x for x, y in zip(ea, eb, strict=True))
    weights: dict[Atom, float] = {Atom((0, 0), func, plus): 0.5}
    weights[Atom((0, 0), func, minus)] = 0.5
    for i in range(1, a + 2):  # w_a w_b = sum over joints i <= a, j <= b of qd_i qd_j
        for j in range(1, b + 2):
            key = Atom((min(i, j), max(i, j)), func, minus)
            weights[key] = weights.get(key, 0.0) + 1.0
    return Combination(tuple(weights.items()))


def link_rate_atom(a: int) -> Atom | Combination:
    """w_a^2 of chain link a (0-based), w_a = qd_2 + ... + qd_(a+2): the link's own
    rotational energy in the chain's plane."""
    if a == 0:
        return Atom((1, 1))
    joints = range(1, a + 2)
    return Combination(tuple((Atom((i, j)), 1.0 if i == j else 2.0)
                             for i in joints for j in joints if i <= j))


def _tied(atoms: list[Atom], dof: int, symmetric_links: bool) -> list:
    """The chain's kinetic atoms of rigid links plus rotors: w_a^2 per link, qd_j^2 per
    rotor of the distal joints (the first chain joint's rotor is w_1^2 itself), and one
    Combination per link pair and function for the relative-angle and base reach terms."""
    pairs = [(a, b) for a in range(dof - 1) for b in range(a + 1, dof - 1)]
    combos = [link_pair_atoms(dof, a, b, f) for a, b in pairs for f in _funcs(symmetric_links)]
    covered = {part for c in combos for part, _ in c.parts}
    # a chain's kinetic term comes from a link, a rotor or a link pair (never qd3^2 cos q3)
    kept = [a for a in atoms if a not in covered and not (a.velocities and min(a.velocities) >= 1)]
    rates = [link_rate_atom(a) for a in range(dof - 1)]
    rotors = [Atom((j, j)) for j in range(2, dof)]
    return kept + rates + rotors + combos


def arm_atoms(dof: int = 3, symmetric_links: bool = True, rigid_links: bool = False) -> list:
    """Atoms of a vertical-base arm with a planar chain: spatial atoms on the base plus
    planar atoms on joints 2..dof (a pendulum for dof = 1), duplicates removed; with
    rigid_links, the relative-angle atoms tied per link pair (see `link_pair_atoms`)."""
    if dof < 2:
        return pendulum_atoms()
    atoms = spatial_atoms(dof, symmetric_links)
    atoms += planar_atoms(dof - 1, first=1, total=dof, symmetric=symmetric_links)
    atoms = list(dict.fromkeys(atoms))
    return _tied(atoms, dof, symmetric_links) if rigid_links else atoms


def prior_knowledge_library(dof: int = 3, symmetric_links: bool = True,
                            rigid_links: bool = True) -> Library:
    """The library of a vertical-base arm with a planar chain, composed from the simple
    structures: spatial atoms on the base plus planar atoms on joints 2..dof; its atoms
    tied per rigid link pair unless rigid_links is False."""
    suffix = "" if symmetric_links or dof < 2 else "-general"
    suffix += "" if rigid_links or dof < 3 else "-untied"
    return derive(arm_atoms(dof, symmetric_links, rigid_links), dof, f"prior-{dof}dof{suffix}")[0]
