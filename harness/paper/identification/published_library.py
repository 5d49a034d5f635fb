"""The paper's published 75-feature library for its 3-DOF arm (authors' sindy.py)."""

from __future__ import annotations

from identification.library.base import Library
from identification.library.features import Feature, Trig, motion

_PAPER_ANGLES = [(0, 1, 0), (0, 0, 1), (0, 2, 0), (0, 0, 2), (0, 1, 1), (0, 2, 1), (0, 2, 2)]
_PAPER_SIN = [(0, 0, 1), (0, 2, 1), (0, 2, 2)]


def paper_library() -> Library:
    """The 75-feature 3-DOF library exactly as published (authors' sindy.py, in that order).

    {qdd_i, qd1 qd2, qd2 qd3, qd1 qd3} x cos{q2, q3, 2q2, 2q3, q2+q3, 2q2+q3, 2q2+2q3}
    (42), {qd_i^2} x sin{q3, 2q2+q3, 2q2+2q3} (9), {qdd_i, qd_i qd_j} x those sines
    (18), cos q2, cos(q2+q3), qd1^2 sin 2q2, qdd1, qdd2, qdd3 (6).
    """
    a = [motion(m) if " " not in m else motion(*m.split()) for m in
         ("qdd1", "qdd2", "qdd3", "qd1 qd2", "qd2 qd3", "qd1 qd3")]
    b = [motion("qd1", "qd1"), motion("qd2", "qd2"), motion("qd3", "qd3")]
    feats = [Feature(m, (Trig("cos", c),)) for m in a for c in _PAPER_ANGLES]
    feats += [Feature(m, (Trig("sin", c),)) for m in b for c in _PAPER_SIN]
    feats += [Feature(m, (Trig("sin", c),)) for m in a for c in _PAPER_SIN]
    feats += [Feature((), (Trig("cos", (0, 1, 0)),)), Feature((), (Trig("cos", (0, 1, 1)),)),
              Feature(b[0], (Trig("sin", (0, 2, 0)),))]
    feats += [Feature(m) for m in a[:3]]
    return Library("paper-75", 3, tuple(feats))
