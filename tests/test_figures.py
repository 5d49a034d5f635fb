"""The figures the README and the docs state, recomputed under uv.lock (issue #68): every figure
is read from the doc's own text, with the command the doc gives for it, the command is run as
`torquebench plan` (in-process), and the measured value must round to the stated digits, so a
doc and its check cannot drift apart. Read here:

- README.md: what `plan` spends on the UR5 example, one re-planned plan (`--bank 1`) and the
  penalty loop (`--replanner penalty`), the command docs/planning.md's 'The UR5 example' gives;
- docs/planning.md, 'The UR5 example': the same three energies, the bank's switch under the
  forearm and the clearance kept;
- docs/realtime.md, 'Measured' ('The bank of plans'): the nine UR5 and Panda crossings under
  uv.lock, each planned three ways (the table's columns).

27 plans, each run once whatever number of figures it checks: 4.0 min serially on a shared
2-core machine, 4.6 min with the planning problems compiled afresh (an empty
$TORQUEBENCH_CACHE). Marked slow:
`make check-figures` runs this file alone, `make test-slow` (CI) with the other slow tests.
What the docs must keep saying for the check to read them is tested fast
(`test_the_docs_state_every_figure_the_check_reads`)."""

from __future__ import annotations

import json
import re
import shlex
from dataclasses import dataclass
from pathlib import Path

import pytest

from harness.cli import main

ROOT = Path(__file__).resolve().parents[1]
N = r"(\d+\.\d+)"
LOCK_TABLE = "**Under uv.lock**"  # the paragraph in docs/realtime.md whose table is checked


@dataclass(frozen=True)
class Figure:
    where: str  # the doc and what the figure is
    command: tuple[str, ...]  # plan's arguments, as the doc gives them
    key: str  # "energy", "min_clearance" (m) or "switch" (s: the bank's first class switch)
    stated: str  # as the doc writes it: its digits are the check's tolerance


def _flat(text: str) -> str:
    """Whitespace collapsed: the docs wrap their sentences anywhere."""
    return " ".join(text.split())


def _read(name: str) -> str:
    return (ROOT / name).read_text()


def _section(text: str, heading: str) -> str:
    """From the heading's line to the next heading of its level or above."""
    level = heading.split(" ")[0]
    start = text.index(f"\n{heading}\n")
    ends = [m.start() for m in re.finditer(r"\n(#+) ", text[start + 1:])
            if len(m.group(1)) <= len(level)]
    return text[start:start + 1 + ends[0]] if ends else text[start:]


def _match(pattern: str, text: str, where: str) -> re.Match:
    found = re.search(pattern, _flat(text))
    assert found, f"{where}: the sentence the figures check reads is gone or reworded " \
                  f"(tests/test_figures.py: {pattern})"
    return found


def _plan_args(line: str, values: dict | None = None) -> tuple[str, ...]:
    """`torquebench plan ...` as plan's arguments, without --out and its value; a word that
    is a key of values replaced by its value."""
    words = [(values or {}).get(word, word) for word in shlex.split(line)]
    assert words[:2] == ["torquebench", "plan"], line
    args, skip = [], False
    for word in words[2:]:
        if skip or word == "--out":
            skip = not skip
            continue
        args.append(word)
    return tuple(args)


def ur5_example() -> tuple[str, ...]:
    """The plan command of docs/planning.md's 'The UR5 example' (its code block)."""
    section = _section(_read("docs/planning.md"), "## The UR5 example")
    block = re.search(r"```sh\n(.*?)```", section, re.S).group(1).replace("\\\n", " ")
    return _plan_args(next(line for line in block.splitlines()
                           if line.strip().startswith("torquebench plan")))


def _options(cell: str) -> tuple[str, ...]:
    """A column's options: `default` none, else what its backticks hold."""
    cell = cell.strip()
    return () if cell == "default" else tuple(shlex.split(cell.strip("`")))


def readme_figures() -> list[Figure]:
    example = ur5_example()
    found = _match(rf"on the UR5 crossing of \[docs/planning\.md\]\(docs/planning\.md\) it spends "
                   rf"{N} J, where one re-planned plan spent {N} J and the paper's penalty loop "
                   rf"{N} J", _read("README.md"), "README.md")
    ways = (("the bank (default)", ()), ("one re-planned plan", ("--bank", "1")),
            ("the penalty loop", ("--replanner", "penalty")))
    return [Figure(f"README.md: the UR5 example, {name}: energy (J)", example + options,
                   "energy", stated)
            for (name, options), stated in zip(ways, found.groups(), strict=True)]


def planning_figures() -> list[Figure]:
    example = ur5_example()
    found = _match(rf"`plan` spends {N} J there \(the bank passes under the forearm from "
                   rf"t = {N} s\), keeping {N} m[^;]*; `(--[^`]+)` spends {N} J, over it, and "
                   rf"`(--[^`]+)` {N} J, under it",
                   _section(_read("docs/planning.md"), "## The UR5 example"),
                   "docs/planning.md, 'The UR5 example'")
    bank, switch, clearance, one, one_energy, other, other_energy = found.groups()
    where = "docs/planning.md: the UR5 example"
    return [Figure(f"{where}, the bank: energy (J)", example, "energy", bank),
            Figure(f"{where}, the bank: switch under the forearm (s)", example, "switch", switch),
            Figure(f"{where}, the bank: min clearance (m)", example, "min_clearance", clearance),
            Figure(f"{where}, `{one}`: energy (J)", example + tuple(shlex.split(one)), "energy",
                   one_energy),
            Figure(f"{where}, `{other}`: energy (J)", example + tuple(shlex.split(other)),
                   "energy", other_energy)]


def crossing_figures() -> list[Figure]:
    """docs/realtime.md's nine crossings under uv.lock: the command the paragraph gives (R, A
    and B from each row), each column's options from its header."""
    text = _read("docs/realtime.md")
    start = text.index(LOCK_TABLE)
    paragraph = text[start:text.index("\n\n", start)]
    command = _match(r"`(torquebench plan --robot R [^`]*--obstacle-from A --obstacle-to B)`",
                     paragraph, "docs/realtime.md, 'Under uv.lock'").group(1)
    rows = [line for line in text[start:].split("\n\n")[1].splitlines()
            if line.startswith("|") and not line.startswith("|---")]
    header, rows = [c.strip() for c in rows[0].strip("|").split("|")], rows[1:]
    assert header[:2] == ["robot", "obstacle from -> to"], header
    figures = []
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        source, target = cells[1].split(" (")[0].split(" -> ")
        base = _plan_args(command, {"R": cells[0], "A": source, "B": target})
        for column, stated in zip(header[2:], cells[2:], strict=True):
            figures.append(Figure(f"docs/realtime.md, under uv.lock: {cells[0]} {cells[1]}, "
                                  f"{column}: energy (J)", base + _options(column), "energy",
                                  stated))
    return figures


def stated_figures() -> list[Figure]:
    return readme_figures() + planning_figures() + crossing_figures()


def by_command() -> dict[tuple[str, ...], list[Figure]]:
    commands: dict[tuple[str, ...], list[Figure]] = {}
    for figure in stated_figures():
        commands.setdefault(figure.command, []).append(figure)
    return commands


def test_the_docs_state_every_figure_the_check_reads():
    """Fast: the sentences and the table are where the check reads them (3 figures in the
    README, 5 in docs/planning.md, 9 crossings x 3 ways in docs/realtime.md), each a number with
    its digits, and the README's figures are the ones docs/planning.md states for the same
    commands."""
    readme, planning, crossings = readme_figures(), planning_figures(), crossing_figures()
    assert (len(readme), len(planning), len(crossings)) == (3, 5, 27)
    assert len(by_command()) == 27  # the UR5 example's three plans are the table's first row
    stated = {(f.command, f.key): f.stated for f in planning + crossings}
    for figure in readme:
        assert stated[figure.command, figure.key] == figure.stated, figure


def _measured(plan: dict, key: str) -> float:
    if key == "switch":
        return plan["bank"]["switches"][0]["t"]
    return plan[key]


@pytest.mark.slow
@pytest.mark.parametrize("command", list(by_command()), ids=" ".join)
def test_the_stated_figure_is_what_the_command_gives(command, tmp_path):
    """Each figure stated for this command equals what it gives, to the stated digits."""
    out = tmp_path / "plan.json"
    assert main(["plan", *command, "--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    wrong = []
    for figure in by_command()[command]:
        digits = len(figure.stated.split(".")[1])
        measured = f"{_measured(plan, figure.key):.{digits}f}"
        if measured != figure.stated:
            wrong.append(f"{figure.where}: stated {figure.stated}, measured {measured}")
    assert not wrong, f"torquebench plan {shlex.join(command)}:\n" + "\n".join(wrong)
