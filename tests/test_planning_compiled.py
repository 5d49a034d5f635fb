"""Quick builds (planning.formulation.compiled, issue 43 item 7): every unit at -O0, a large
function's C split into units (planning.formulation.c_units) built in parallel; the same bits
as the optimized build, which is used instead once cached; code of another shape left whole.
The plan command's plan is the same with either build (slow: two builds of the Lynxmotion's
planner), and it says each compile stage on a terminal."""

from __future__ import annotations

import json
import logging
import re

import casadi as ca
import numpy as np
import pytest

from harness.cli import main
from planning.formulation import c_units, compiled
from planning.result import TIMING_KEYS

pytestmark = pytest.mark.skipif(not compiled.available(), reason="no C compiler")


def _function(steps: int = 15) -> ca.Function:
    """A function shaped as the planner's: a site called (never inlined) at every step of a
    recursion, its outputs and the Hessian of their sum (locals reused across the body)."""
    x, p, z = ca.SX.sym("x", 6), ca.SX.sym("p", 3), ca.SX.sym("z", 3)
    site = ca.Function("site", [z], [ca.vertcat(ca.sin(z[0]) * z[1],
                                                ca.exp(0.1 * z[2]) + ca.fmax(z[0], z[1]))],
                       {"never_inline": True})
    state, terms = x, []
    for k in range(steps):
        s = site(ca.vertcat(state[k % 6], p[k % 3], state[(k + 1) % 6]))
        state = ca.vertcat(state[1:], s[0] * state[0] + s[1] / (1 + state[2] ** 2))
        terms.append(ca.dot(state, state) * ca.sqrt(ca.fabs(s[0]) + 1))
    total = ca.sum1(ca.vertcat(*terms))
    return ca.Function("shaped", [x, p], [ca.vertcat(*terms), ca.vec(ca.hessian(total, x)[0])])


@pytest.fixture
def builds(tmp_path, monkeypatch):
    """The cache in tmp_path, small parts, and the compiler commands run."""
    monkeypatch.setenv("TORQUEBENCH_CACHE", str(tmp_path))
    monkeypatch.setattr(compiled, "PART_BYTES", 20_000)
    commands: list[list[str]] = []
    run = compiled._run
    monkeypatch.setattr(compiled, "_run", lambda command: (commands.append(command),
                                                           run(command)))
    return commands


def _outputs(f: ca.Function, points: int = 20) -> list[np.ndarray]:
    rng = np.random.default_rng(0)
    return [np.concatenate([np.asarray(out).ravel() for out in
                            f(rng.uniform(-2, 2, 6), rng.uniform(0.1, 2, 3))])
            for _ in range(points)]


def test_a_quick_build_splits_a_large_function_and_gives_the_optimized_bits(builds):
    f = _function()
    quick = compiled.function(f, quick=True)
    units = [c for c in builds if "-c" in c]
    assert len(units) > 3 and all("-O0" in c for c in units)
    builds.clear()
    optimized = compiled.function(f)
    assert [c for c in builds if "-c" in c] and all("-O1" in c for c in builds if "-c" in c)
    for a, b, c in zip(_outputs(quick), _outputs(optimized), _outputs(f), strict=True):
        assert np.array_equal(a, b) and np.allclose(a, c, rtol=1e-12, atol=1e-12)
    builds.clear()
    compiled.function(f, quick=True)  # the optimized library is cached now: taken as it is
    assert builds == []


def test_parts_that_pass_no_locals_on_give_other_numbers(builds, monkeypatch):
    """The comparison above catches a split that loses the locals its parts share."""
    split, f = c_units.split, _function()

    def dropped(text: str, part_bytes: int) -> list[str]:
        return [re.sub(r"(?m)^  live\[\d+\] = a\d+;\n", "", unit)
                for unit in split(text, part_bytes)]

    monkeypatch.setattr(c_units, "split", dropped)
    broken = compiled.function(f, quick=True)
    assert not all(np.array_equal(a, b, equal_nan=True)
                   for a, b in zip(_outputs(broken), _outputs(f), strict=True))


def test_code_of_another_shape_is_left_whole():
    text = ("#include <math.h>\nstatic int casadi_f0(const casadi_real** arg, casadi_real** "
            "res, casadi_int* iw, casadi_real* w, int mem) {\n  casadi_real a0;\n"
            + "  for (a0=0; a0<3; ++a0) { w[0] += a0; }\n" * 2000 + "  return 0;\n}\n")
    assert c_units.split(text, 1000) == [text]
    assert c_units.split("int x;\n", 1) == ["int x;\n"]


@pytest.mark.slow
def test_the_plan_is_the_same_with_the_quick_and_the_optimized_build(tmp_path, monkeypatch):
    """plan on the Lynxmotion with an empty cache (the quick build) and with the optimized
    build cached by a --realtime run first: the same PLAN.json apart from its timing keys."""
    plans = []
    for name, first in (("quick", None), ("optimized", "--realtime")):
        monkeypatch.setenv("TORQUEBENCH_CACHE", str(tmp_path / name))
        out = tmp_path / f"{name}.json"
        if first:
            assert main(["plan", "--model", "pinocchio", first, "--out", str(out)]) == 0
        assert main(["plan", "--model", "pinocchio", "--out", str(out)]) == 0
        plans.append(json.loads(out.read_text()))
    levels = {name: {p.name for p in (tmp_path / name / "nlp").glob("*.so")}
              for name in ("quick", "optimized")}
    assert levels["quick"].isdisjoint(levels["optimized"])  # two different builds
    for plan in plans:
        for key in TIMING_KEYS:
            plan.pop(key)
    assert plans[0] == plans[1]


def test_the_plan_command_says_each_compile_stage_on_a_terminal(monkeypatch, capsys):
    """One line as each stage of 100 kB or more starts, with the time so far, and the total;
    nothing when stderr is not a terminal."""
    from harness.plan.messages import BuildNotice

    notice = BuildNotice("panda", 7)
    monkeypatch.setattr("sys.stderr.isatty", lambda: True)
    for stage, kilobytes in (("the NLP solvers' functions", 5373), ("a small one", 14),
                             ("the safety checks", 2133)):
        notice.emit(_record(stage, kilobytes, False))
        notice.emit(_record(stage, kilobytes, True))
    notice.finish()
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 3 and all(line.startswith("torquebench: compiling the planner for "
                                                   "panda (7 joints): ") for line in lines)
    assert "first time only" in lines[0] and "5373 kB of C at -O0" in lines[0]
    assert " s, the safety checks" in lines[1] and "done in" in lines[2]
    monkeypatch.setattr("sys.stderr.isatty", lambda: False)
    quiet = BuildNotice("panda", 7)
    quiet.emit(_record("the safety checks", 2133, False))
    quiet.finish()
    assert capsys.readouterr().err == ""


def test_a_first_plan_says_how_long_compiling_took_on_any_stderr(monkeypatch):
    """The plan's line (written or refused) ends with the time compiling took, terminal or
    not; nothing when nothing was compiled."""
    from harness.plan import messages
    from harness.plan.messages import BuildNotice

    clock = iter([10.0, 40.0, 41.0, 53.5])  # two stages: 30 s and 12.5 s
    monkeypatch.setattr(messages.time, "perf_counter", lambda: next(clock))
    monkeypatch.setattr("sys.stderr.isatty", lambda: False)
    notice = BuildNotice("panda", 7)
    assert notice.compiled_note() == ""
    for stage in ("the NLP solvers' functions", "the safety checks"):
        notice.emit(_record(stage, 2000, False))
        notice.emit(_record(stage, 2000, True))
    assert notice.compiled_note().startswith("; compiling the planner took 42.5 s of this run")


def _record(stage: str, kilobytes: int, done: bool) -> logging.LogRecord:
    record = logging.LogRecord(compiled.log.name, logging.INFO, __file__, 0, "compiling", (),
                               None)
    record.stage, record.kilobytes, record.level, record.done = stage, kilobytes, "-O0", done
    return record
