"""What every bench section and study is given and returns.

A section (harness/bench/<name>) and a study (harness/studies/<name>) are modules with
`run(context: Context) -> SectionResult`. They separate two kinds of figures:

- a `Check` must hold whenever the software is correct (a cross-check against an
  independent implementation, an invariant, a physical bound): one that fails makes the
  bench exit non-zero;
- a `Target` is what the project aims at (a speed or accuracy goal): reported with the
  measured figure, the target and the gap, never changing the exit status.

Timing-dependent figures (seconds, CPU times, anything a deadline decides) are declared as
such (`Target.timing`, results under a key `timing`): everything else in a report is the
same on every run of the same configuration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from harness.robots.arm import Arm


@dataclass(frozen=True)
class Check:
    """Something that must hold; `detail` says what was measured."""

    name: str
    passed: bool
    detail: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "passed", bool(self.passed))  # numpy bools count too


@dataclass(frozen=True)
class Target:
    """A goal: `measured` against `target` in `unit`; lower is better unless said."""

    name: str
    measured: float | None
    target: float
    unit: str = ""
    lower_is_better: bool = True
    timing: bool = False  # the figure depends on the machine's speed and load
    note: str = ""

    @property
    def met(self) -> bool | None:
        if self.measured is None or not math.isfinite(self.measured):
            return None
        return self.measured <= self.target if self.lower_is_better else self.measured >= self.target

    @property
    def gap(self) -> float | None:
        """How far the measured figure is from the target, in its direction (0 when met)."""
        if self.met is None:
            return None
        short = self.measured - self.target if self.lower_is_better else self.target - self.measured
        return max(0.0, float(short))


@dataclass(frozen=True)
class Row:
    """One line of the report's headline: a question and what was measured."""

    question: str
    measured: str


@dataclass
class SectionResult:
    """What a section or study produced. `outputs` are handed to later sections in memory
    (an identified model, plans) and are not written."""

    markdown: str
    results: dict = field(default_factory=dict)
    checks: list[Check] = field(default_factory=list)
    targets: list[Target] = field(default_factory=list)
    headline: list[Row] = field(default_factory=list)
    figures: list[Path] = field(default_factory=list)
    outputs: dict[str, Any] = field(default_factory=dict)

    def extend(self, other: SectionResult, name: str) -> None:
        """Add a robot-declared extra's work (harness.robots.extras) under its name: its
        text as a subsection, its checks and targets prefixed, its results under name, its
        plans beside this section's."""
        self.markdown += f"\n\n### {name}\n\n{other.markdown}"
        self.results[name] = other.results
        self.checks += [Check(f"{name}.{c.name}", c.passed, c.detail) for c in other.checks]
        self.targets += [replace(t, name=f"{name}: {t.name}") for t in other.targets]
        self.headline += other.headline
        self.figures += other.figures
        for key, value in other.outputs.items():
            mine = self.outputs.setdefault(key, {})
            mine.update(value)


@dataclass(frozen=True)
class Context:
    """A run of the bench or of a study: the arm (resolved once), where to write, how much to
    do, and the results of the sections that ran before (by name)."""

    arm: Arm
    out_dir: Path
    quick: bool = False
    video: bool = True
    earlier: dict[str, SectionResult] = field(default_factory=dict)

    @property
    def figures_dir(self) -> Path:
        path = Path(self.out_dir) / "figures"
        path.mkdir(parents=True, exist_ok=True)
        return path

    def output(self, section: str, key: str, default=None):
        """What an earlier section handed on under key (default if it did not run)."""
        earlier = self.earlier.get(section)
        return default if earlier is None else earlier.outputs.get(key, default)


def check(name: str, passed, detail: str = "") -> Check:
    return Check(name, bool(passed), detail)


MAX_DIGITS = 6  # significant digits distinct() goes up to


def distinct(values, digits: int = 3) -> list[str]:
    """values printed with `digits` significant digits, more (up to MAX_DIGITS) where two
    that differ would read the same: figures a table compares never look equal when not."""
    values = [float(v) for v in values]
    for n in range(digits, MAX_DIGITS + 1):
        texts = [f"{v:.{n}g}" for v in values]
        if all(texts[i] != texts[k] or values[i] == values[k]
               for i in range(len(values)) for k in range(i)):
            break
    return texts
