"""The bank's executed energy against the causal multi-start reference on chosen Lynxmotion
scenarios of the bank study's machinery (harness.studies.bank: `draw`, `planned`, `causal`):
how the bank's classes and search seeds (planning.bank.classes, the base's way;
planning.globalsearch.starts.turned_away) are measured, on development scenarios and fresh
ones (docs/realtime.md, 'The base's way').

Seed 3968 (FRESH): drawn once (numpy's default_rng, 2026-12-07) after the base's way and its
seed were set on the development scenarios (the bank study's 20, seed 9784, scenario 4 among
them); no setting was chosen on its scenarios.

    python -m harness.studies.bank_ways SEED COUNT [CACHE.json]

prints each scenario's bank energy (J), its smallest clearance over the threshold (mm), the
causal reference's energy and feasibility, the excess (%), and how many of those whose
reference is feasible are within 0.5 % or below; the references are kept in CACHE.json
(they do not depend on the bank) so that a rerun on other code plans only the bank.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from harness.bench.planning.section import CAUSAL_STARTS
from harness.studies.bank import WITHIN, causal, draw, planned

FRESH = 3968  # drawn once; see the module's docstring
ROBOT = "lynxmotion"


def measured(seed: int, count: int, cache: Path | None = None) -> list[dict]:
    """Each scenario's bank execution and causal reference (read from cache if there)."""
    known = json.loads(cache.read_text()) if cache is not None and cache.exists() else {}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, scenario in enumerate(draw(ROBOT, count, seed)):
            bank = planned(ROBOT, scenario, (), Path(tmp) / f"{i}.json")
            key = f"{seed}:{i}"
            if key not in known:
                found = causal(ROBOT, scenario, {"energy": 1.0}, CAUSAL_STARTS)
                known[key] = {k: found[k] for k in ("reference_J", "reference_feasible")}
            reference = known[key]
            energy = bank.get("energy")
            excess = None if energy is None else 100 * (energy / reference["reference_J"] - 1)
            rows.append({"scenario": i, "bank": bank, "reference_J": reference["reference_J"],
                         "reference_feasible": reference["reference_feasible"],
                         "excess_pct": excess})
            if cache is not None:
                cache.write_text(json.dumps(known, indent=1))
    return rows


def lines(rows: list[dict]) -> list[str]:
    out = ["| # | bank (J) | clearance - threshold (mm) | reference (J) | feasible | excess |",
           "|---|---|---|---|---|---|"]
    for r in rows:
        bank = r["bank"]
        kept = "-" if "energy" not in bank else \
            f"{1e3 * (bank['min_clearance'] - bank['threshold']):+.1f}"
        energy = f"{bank['energy']:.4f}" if "energy" in bank else "refused"
        excess = "-" if r["excess_pct"] is None else f"{r['excess_pct']:+.2f} %"
        out.append(f"| {r['scenario']} | {energy} | {kept} | {r['reference_J']:.4f} | "
                   f"{'yes' if r['reference_feasible'] else 'no'} | {excess} |")
    feasible = [r for r in rows if r["reference_feasible"]]
    good = sum(r["excess_pct"] is not None and r["excess_pct"] <= 100 * WITHIN for r in feasible)
    out.append(f"\nwithin 0.5 % of the causal reference or below: {good} of {len(feasible)} "
               f"whose reference is feasible ({len(rows) - len(feasible)} apart)")
    return out


if __name__ == "__main__":
    args = sys.argv[1:]
    print("\n".join(lines(measured(int(args[0]), int(args[1]),
                                   Path(args[2]) if len(args) > 2 else None))))
