"""The global search beside the real-time loop (planning.globalsearch): it escapes a warm
start in the wrong homotopy class where the anytime SQP's re-plan cannot, the same command
gives the same plan with it on the nominal clock, IPOPT on the elastic NLP (the realtime
study's reference) agrees with the penalty loop, and the plan's report counts adoptions."""

from __future__ import annotations

import dataclasses
import math
import multiprocessing
import time

import numpy as np
import pytest

from harness.robots.arm import Arm
from planning.anytime.planner import AnytimePlanner
from planning.globalsearch import background
from planning.globalsearch.ipopt import IpoptElastic
from planning.globalsearch.multistart import MultiStart, objective
from planning.globalsearch.planner import ADOPTED, GlobalSearchPlanner, report
from planning.penalty.solver import Planner
from planning.planners import executed
from planning.types import Segment
from tests.helpers import lynx_default_config, lynx_scenario, random_crossing


@pytest.fixture(scope="module")
def baseline():
    return Arm.of("lynxmotion").nominal


@pytest.fixture(scope="module")
def config():
    return lynx_default_config(compile_code=False, torque_limit=None).with_anytime(
        iteration_ms=0.5)


def test_the_search_escapes_a_warm_start_in_the_wrong_class(baseline, config):
    """On a random crossing, the worst safe plan of the search's own starts (the obstacle
    passed the other way) as warm start: the anytime SQP's 10 ms re-plan from it stays
    dearer than the search from the same warm start, which reaches the best start's plan."""
    numbers = Planner(baseline, config)
    case, forecast = random_crossing(numbers, seed=3)
    search = MultiStart(baseline, config)
    segment = Segment.of(case, forecast)
    best, plans = search.search(segment)
    scores = [objective(search.check, config, plan, 0.0, case.duration, forecast)
              for plan in plans]
    safe = [i for i, score in enumerate(scores) if not score[0]]
    worst = max(safe, key=lambda i: scores[i][1])
    wrong = plans[worst]
    assert scores[worst][1] > 1.05 * min(scores[i][1] for i in safe)  # another class
    anytime = AnytimePlanner(baseline, config)
    replan = anytime.plan(dataclasses.replace(segment, realtime=True), warm=wrong)
    found, _ = search.search(segment, warm=wrong)
    ours, theirs = (objective(search.check, config, plan, 0.0, case.duration, forecast)
                    for plan in (replan, found))
    assert not theirs[0] and theirs[1] <= ours[1]
    assert theirs[1] <= objective(search.check, config, best, 0.0, case.duration,
                                  forecast)[1] + 1e-6
    assert theirs[1] < 0.99 * scores[worst][1]


def test_the_same_scenario_twice_gives_the_same_plan(baseline, config):
    """Algorithm 2 with the global search on the nominal clock, twice in one process (the
    searches' planners and estimates warm the second time): identical segments, and a
    search's plan adopted."""
    runs = [executed(baseline, config, lynx_scenario())[1] for _ in range(2)]
    first, second = (run.execution.segments for run in runs)
    assert len(first) == len(second)
    for a, b in zip(first, second, strict=True):
        assert a.status == b.status
        np.testing.assert_array_equal(a.trajectory.coefficients, b.trajectory.coefficients)
    adopted = sum(s.status.endswith(ADOPTED) for s in first)
    assert adopted >= 1 and report(config, first)["adoptions"] == adopted


def test_ipopt_on_the_elastic_nlp_agrees_with_the_penalty_loop(baseline, config):
    """With the obstacle far from the motion (screened out) neither penalty binds: IPOPT on
    the elastic NLP and the penalty loop's converged solve without obstacle reach the same
    energy from the same start (the initial guess)."""
    far = dataclasses.replace(config, replanner="penalty").with_penalty(solver="ipopt")
    numbers = Planner(baseline, far)
    case, forecast = random_crossing(numbers, seed=5)
    forecast = dataclasses.replace(forecast, centres=forecast.centres + 5.0)
    penalty = numbers.solve(Segment.of(case))
    elastic = IpoptElastic(baseline, config).solve(Segment.of(case, forecast))
    assert penalty.success and elastic.success
    assert elastic.penalty == pytest.approx(0.0, abs=1e-9)
    assert elastic.energy == pytest.approx(penalty.energy, rel=1e-5)


def test_ipopt_plans_count_their_work_on_the_budgets_clock(baseline, config):
    """IPOPT's plans carry clock_ms as the anytime SQP's do (planning.anytime.budget.Clock):
    nominally iteration_ms per IPOPT iteration and Clock.ROUND_ITERATIONS per screening
    round, under CPU clocks the solve's CPU; they carried 0, and a nominal-clock search by
    IPOPT offered its plans as free work (#56 item 11)."""
    from planning.anytime.budget import Clock
    from planning.globalsearch.ipopt import ROUNDS

    case, forecast = random_crossing(Planner(baseline, config), seed=5)
    segment = Segment.of(case, forecast)
    nominal = IpoptElastic(baseline, config).solve(segment)
    ticks = nominal.clock_ms / config.anytime.iteration_ms - nominal.iterations
    rounds = ticks / Clock.ROUND_ITERATIONS
    assert nominal.iterations > 0 and rounds == pytest.approx(round(rounds), abs=1e-9)
    assert 1 <= round(rounds) <= ROUNDS
    live = IpoptElastic(baseline, config.with_anytime(iteration_ms=None)).solve(segment)
    assert live.iterations == nominal.iterations
    assert 0 < live.clock_ms <= live.solve_cpu_ms + 1e-6


def test_with_one_core_the_real_time_loop_runs_alone(baseline, config, monkeypatch):
    """Under CPU clocks on one core no search runs and the report says so."""
    monkeypatch.setattr(background, "cores", lambda: 1)
    monkeypatch.setattr("planning.globalsearch.planner.cores", lambda: 1)
    live = config.with_anytime(iteration_ms=None)
    planner = GlobalSearchPlanner(AnytimePlanner(baseline, live), baseline, live)
    assert planner.mode == "one core"
    case = lynx_scenario()
    first = planner.plan(Segment.of(case, None, budget_ms=math.inf))
    assert not planner.offers(0.5)
    assert "one core" in report(live, (first,))["mode"]
    assert planner.searches == 0


def test_each_better_plan_enters_when_the_search_work_up_to_it_is_done(baseline, config,
                                                                      monkeypatch):
    """On the nominal clock every plan a search offers enters at the first obstacle sample
    at least `lag` samples after the re-plan and after the re-plan's own work plus the search's
    work up to that plan (its starts in order) on the nominal clock (the other core cannot
    hand it over sooner, nor start before the re-plan it searches from); each offer better
    than the one before, the last the search's best (when that enters before the motion's
    settle horizon). With a lag of one sample, shorter than any search, the work decides, and
    a plan found early in a search enters before the search is done."""
    config = config.with_global_search(lag=1)
    searches = []
    search = MultiStart.search

    def recorded(self, *args, **kwargs):
        best, plans = search(self, *args, **kwargs)
        searches.append((args, best, plans))
        return best, plans

    monkeypatch.setattr(MultiStart, "search", recorded)
    launch = GlobalSearchPlanner._launch
    checked, early = [], []

    def launched(self, problem, warm, after_ms=0.0):
        before = len(searches)
        launch(self, problem, warm, after_ms)
        if len(searches) == before or not self._offers:
            return
        args, best, plans = searches[-1]
        period = float(problem.forecast.times[1] - problem.forecast.times[0])
        work = (after_ms + np.cumsum([plan.clock_ms for plan in plans])) / (1e3 * period)
        segment = args[0]
        scores = [objective(self.check, config, plan, segment.t_begin, segment.duration,
                            segment.forecast) for _, plan in self._offers]
        assert scores == sorted(scores, reverse=True) and len(set(scores)) == len(scores)
        for due, plan in self._offers:
            index = next(i for i, p in enumerate(plans) if p is plan)
            samples = max(config.global_search.lag, math.ceil(work[index] - 1e-9))
            assert due - problem.t_begin == pytest.approx(samples * period, abs=1e-9)
            checked.append(samples)
            early.append(samples < work[-1] - 1)
        every = [objective(self.check, config, plan, segment.t_begin, segment.duration,
                           segment.forecast)
                 for plan in plans]
        first = every.index(min(every))  # the search's best
        assert best.trajectory is plans[first].trajectory
        if self._offers[-1][1] is not plans[first]:  # it would enter too late to be offered
            samples = max(config.global_search.lag, math.ceil(work[first] - 1e-9))
            end = min(problem.t_begin + problem.duration - period, self._settle)
            assert problem.t_begin + samples * period >= end - 1e-9

    monkeypatch.setattr(GlobalSearchPlanner, "_launch", launched)
    executed(baseline, config, lynx_scenario())
    assert checked and max(checked) > 2
    assert any(early)


def test_the_other_process_sends_each_better_plan_as_found(baseline, config):
    """Under CPU clocks the search runs in a worker forked when the Background is made, and
    sends back each plan better than those before: once it is done the worker has sent as many
    plans as the same search in this process finds better, and the plan on offer, taken once,
    is that search's best. A search of a motion forgotten (a new one begins) offers nothing."""
    live = config.with_anytime(iteration_ms=None)
    numbers = Planner(baseline, live)
    case, forecast = random_crossing(numbers, seed=3)
    segment = Segment.of(case, forecast)
    better = []
    here, _ = MultiStart(baseline, live).search(segment, found=lambda plan, b: better.append(b))
    before = {child.pid for child in multiprocessing.active_children()}
    worker = background.Background(baseline, live)
    # forked when made, not at the first search (the pages the planning process wrote after
    # that fork were copied in its first re-plan: docs/realtime.md, 'The first re-plan')
    assert len({child.pid for child in multiprocessing.active_children()} - before) == 1

    def finished():
        for _ in range(6000):
            if not worker.busy():
                return True
            time.sleep(0.01)
        return False

    try:
        assert worker.submit(segment, None) and not worker.submit(segment, None)
        assert finished() and worker.done() and not worker.submit(segment, None)
        assert worker.received == sum(better) >= 2 and worker.failures == 0
        there = worker.ready()
        assert there is not None and worker.ready() is None
        np.testing.assert_allclose(there.trajectory.coefficients,
                                   here.trajectory.coefficients, atol=1e-9)
        assert worker.submit(segment, None)
        worker.forget()
        assert finished() and not worker.done() and worker.ready() is None
    finally:
        worker.close()


def test_a_failed_search_in_the_other_process_is_reported(tmp_path, monkeypatch, capsys):
    """plan --realtime whose every search in the other process raises: the re-plans go on
    without them, PLAN.json's global_search counts the failures and stderr has one note
    (#56 item 8: they were counted and never told)."""
    import concurrent.futures
    import json

    from harness.cli import main
    from planning.globalsearch import planner

    def fails(*args, **kwargs):
        raise RuntimeError("search failed")

    monkeypatch.setattr(planner, "cores", lambda: 2)  # the search in another process
    monkeypatch.setattr(MultiStart, "search", fails)  # in the worker too: it is forked
    submit = background.Background.submit

    def submitted(self, *args):  # the search has failed before the loop goes on
        started = submit(self, *args)
        if started:
            concurrent.futures.wait([self._future])
        return started

    monkeypatch.setattr(background.Background, "submit", submitted)
    out = tmp_path / "plan.json"
    assert main(["plan", "--model", "pinocchio", "--realtime", "--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    assert plan["global_search"]["mode"].startswith("another process")
    failures = plan["global_search"]["failures"]
    assert failures >= 1
    notes = [line for line in capsys.readouterr().err.splitlines() if "global search" in line]
    assert len(notes) == 1 and f"{failures} global search" in notes[0]


def test_the_clearance_that_launches_a_search_is_numpys(baseline, config):
    """The clearance a search's launch reads (compiled) equals planning.formulation's numpy
    predicted_clearance on the search's own plans of a random crossing, from a later
    re-plan's time on (a forecast of the samples left)."""
    from planning.formulation.clearance import predicted_clearance
    from planning.replanning import forecast_at

    numbers = Planner(baseline, config)
    case, forecast = random_crossing(numbers, seed=3)
    _, plans = MultiStart(baseline, config).search(Segment.of(case, forecast))
    planner = GlobalSearchPlanner(AnytimePlanner(baseline, config), baseline, config)
    later = forecast_at(case.obstacle, 0.5)
    for plan in plans:
        motion = plan.trajectory.restrict(0.5, case.duration - 0.5)
        for seen in (forecast, later):
            assert planner.check.clearance(motion, seen.times, seen.centres) == pytest.approx(
                predicted_clearance(config.geometry, motion, seen), abs=1e-9)


@pytest.mark.parametrize("qd0", [(0.0, 0.0, 0.0), (0.4, -0.2, 0.1)])
def test_the_turned_away_start_backs_the_base_off_against_its_way(baseline, config, qd0):
    """The bank's extra start (starts.turned_away): its motion, read back from the NLP's
    point (ProblemNumbers.trajectory), starts at the arm's state, ends at the goal and at
    s = 2/3 has the base detour_rad on the far side of where it started from the goal; the
    other joints as the initial guess has them."""
    from planning.globalsearch.starts import turned_away

    numbers = MultiStart(baseline, config).solver
    q0, goal, duration = np.array([0.1, 1.2, -1.0]), np.array([0.9, 1.0, -0.6]), 2.0
    x = turned_away(numbers, q0, np.asarray(qd0), duration, goal, config)
    motion = numbers.trajectory(x, q0, np.asarray(qd0), 0.0, duration)
    guess = numbers.trajectory(numbers.initial_guess(q0, np.asarray(qd0), duration, goal),
                               q0, np.asarray(qd0), 0.0, duration)
    at = motion.position(np.array([0.0, 2 * duration / 3, duration]))
    assert at[0] == pytest.approx(q0) and at[2] == pytest.approx(goal)
    assert at[1, 0] == pytest.approx(q0[0] - config.global_search.detour_rad)
    assert at[1, 1:] == pytest.approx(guess.position(np.array([2 * duration / 3]))[0, 1:])
    assert motion.state(np.array([0.0]))[1][0] == pytest.approx(qd0)


def _worker_prepared() -> int:
    """In the worker: how many goals its search has prepared (-1: no search built)."""
    search = background._SEARCH
    return -1 if search is None else len(search.solver._prepared)


def test_the_worker_is_ready_when_the_motion_starts(baseline, config, monkeypatch):
    """Under CPU clocks the other process builds its search and the goal's NLPs during the
    first plan, and the first plan returns (the motion starts) once it has: a search
    submitted at the first re-plan starts at once (built at that search, its first plans had
    come ~1.3 s into a Lynxmotion's 2-s motion: docs/realtime.md, 'planning.replanning')."""
    from planning.globalsearch import planner as search_planner
    from planning.replanning import forecast_at

    monkeypatch.setattr(search_planner, "cores", lambda: 2)  # the search in another process
    live = config.with_anytime(iteration_ms=None)
    front = GlobalSearchPlanner(AnytimePlanner(baseline, live), baseline, live, bank=True)
    assert front.mode == "process"
    case = lynx_scenario()
    try:
        front.plan_cold(Segment.of(case, forecast_at(case.obstacle, 0.0)))
        assert not front._background.busy()
        assert front._background._pool.submit(_worker_prepared).result() == 1
    finally:
        front._background.close()


class _Watched:
    """A segment planner whose offers(t) calls are timed from its first plan's end (s)."""

    def __init__(self, inner):
        self.inner, self.config, self.seen = inner, inner.config, []

    def plan_cold(self, problem, starts=None):
        found = self.inner.plan_cold(problem, starts)
        self.motion = time.perf_counter()
        return found

    def offers(self, t):
        self.seen.append((t, time.perf_counter() - self.motion))
        return self.inner.offers(t)

    def __getattr__(self, name):
        return getattr(self.inner, name)


def test_a_paced_motion_takes_each_sample_at_its_time(baseline, config):
    """execute(paced=True), as plan --realtime runs: no obstacle sample is looked at before
    its time after the first plan (the loop ran the 2-s motion in a fraction of that, and the
    other process's search fell behind the motion)."""
    from planning.replanning import execute

    live = config.with_anytime(iteration_ms=None)
    watched = _Watched(AnytimePlanner(baseline, live))
    execute(watched, lynx_scenario(), paced=True)
    assert len(watched.seen) > 100
    assert all(wall >= t - 1e-4 for t, wall in watched.seen)
