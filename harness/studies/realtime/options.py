"""Command-line options shared by the realtime study's tools that run its random
scenarios (ways, oneshot, anatomy)."""

from __future__ import annotations

import argparse
import dataclasses

from harness.studies.realtime import measure as realtime
from planning.config import PlannerConfig

# the split energy quadrature as the tools plan it beside the default (planning.formulation.breaks)
SPLIT = {"energy_quadrature": "split", "power_breaks": 7, "energy_samples": 24}


def parser(doc: str) -> argparse.ArgumentParser:
    """An argument parser described by the first line of `doc`, with --scenarios and --seed."""
    options = argparse.ArgumentParser(description=doc.splitlines()[0])
    options.add_argument("--scenarios", type=int, default=realtime.Setup.scenarios)
    options.add_argument("--seed", type=int, default=realtime.Setup.seed)
    return options


def setup(args: argparse.Namespace) -> realtime.Setup:
    """The study's setup with the scenario count and seed given."""
    return realtime.Setup(scenarios=args.scenarios, seed=args.seed)


def polished(config: PlannerConfig) -> PlannerConfig:
    """8 starts on the default's rule, the best 2 distinct plans polished (PenaltyOptions.polish)."""
    return dataclasses.replace(config, starts=8).with_penalty(polish=2, polish_samples=40)
