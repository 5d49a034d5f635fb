"""The sweep's grid: one cell per (robot, noise, seed, method, samples), parsed from the CLI."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

from harness.errors import UserError

METHODS = ("coupled", "per-joint", "oracle", "stlsq", "ssr")
MIN_SAMPLES = 10  # as harness.data.generate


@dataclass(frozen=True, order=True)
class Cell:
    """One identification: `samples` samples of `robot` at torque noise `noise` (a fraction of
    each joint's torque std), data and noise drawn from `seed`, identified by `method`."""

    robot: str
    noise: float
    seed: int
    method: str
    samples: int

    @property
    def key(self) -> tuple:
        return (self.robot, self.noise, self.seed, self.method, self.samples)

    def label(self) -> str:
        return (f"{self.robot} noise {self.noise:g} seed {self.seed} {self.method} "
                f"{self.samples} samples")


@dataclass(frozen=True)
class Grid:
    """The values of each axis; cells() is their product."""

    robots: tuple[str, ...]
    noise: tuple[float, ...]
    seeds: tuple[int, ...]
    methods: tuple[str, ...]
    samples: tuple[int, ...]

    def cells(self) -> list[Cell]:
        """Every cell, seeds outermost: a sweep stopped early has covered every condition with
        its first seeds."""
        return [Cell(r, n, s, m, k) for s, r, k, n, m in itertools.product(
            self.seeds, self.robots, self.samples, self.noise, self.methods)]

    def __len__(self) -> int:
        return (len(self.robots) * len(self.noise) * len(self.seeds) * len(self.methods)
                * len(self.samples))


def _items(text: str, option: str, convert: Callable, check: Callable, want: str) -> tuple:
    """Comma-separated values, converted and checked, in order, duplicates dropped."""
    out: list = []
    for item in (s.strip() for s in text.split(",")):
        try:
            value = convert(item)
        except ValueError:
            raise UserError(f"{option}: '{item}' is not {want}") from None
        if not check(value):
            raise UserError(f"{option}: '{item}' is not {want}")
        if value not in out:
            out.append(value)
    return tuple(out)


def parse_grid(robots: str, noise: str, seeds: int, methods: str, samples: str) -> Grid:
    """The grid of the CLI's options; UserError with one line on a bad value."""
    if seeds < 1:
        raise UserError(f"--seeds must be a number of seeds >= 1, got {seeds}")
    return Grid(
        robots=_items(robots, "--robots", str, bool, "a robot name or path"),
        noise=_items(noise, "--noise", float, lambda x: math.isfinite(x) and x >= 0,
                     "a finite noise fraction >= 0"),
        seeds=tuple(range(seeds)),
        methods=_items(methods, "--methods", str, lambda m: m in METHODS,
                       f"a method ({', '.join(METHODS)})"),
        samples=_items(samples, "--samples", int, lambda k: k >= MIN_SAMPLES,
                       f"a sample count >= {MIN_SAMPLES}"))
