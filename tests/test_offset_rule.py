"""A held-out run's sensor offset: one rule (identification.closeloop.closed.offsets.held_out_offset)
for identify, closeloop and predict.

Runs of the declared Lynxmotion (its RNEA), each with its own sensor offset and a rest before
its motion whose torque holds a static friction (the rest reads gravity + offset + that
friction): the rule against its closed form (the model's mean residual on the training runs'
samples, pooled: neither the scored run's rest nor its samples), and the three commands
scoring the same held-out run with the same offset and the same error.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from harness.cli import main
from harness.robots.arm import Arm
from identification.closeloop.closed.offsets import (
    first_rest,
    held_out_offset,
    residual_offset,
    run_tail,
    scored_error,
    whole_run,
)
from identification.identify import split_runs
from identification.metrics import rel_error
from tests.helpers import lynxmotion_motion

LYNX = Arm.of("lynxmotion")
REST, SAMPLES, RAMP = 50, 600, 1.0  # samples, samples, s
OFFSETS = ((0.02, -0.01, 0.005), (0.04, 0.01, -0.005), (0.09, -0.03, 0.02))  # per run, N m
STATIC = ((0.03, -0.02, 0.01), (-0.04, 0.02, 0.0), (0.06, 0.05, -0.03))  # at each rest, N m


def _run(k: int, noise: float = 0.0, static: bool = True) -> tuple:
    """Run k: REST samples still, then SAMPLES of a motion that leaves the rest smoothly (its
    displacement faded in over RAMP s); the torque the RNEA's plus OFFSETS[k] everywhere,
    plus STATIC[k] at the rest (static) and white noise."""
    m = lynxmotion_motion(SAMPLES, seed=40 + k, duration=6.0)
    s = np.clip((m.t - m.t[0]) / RAMP, 0.0, 1.0)[:, None]
    w, dw, ddw = (10 * s**3 - 15 * s**4 + 6 * s**5, (30 * s**2 - 60 * s**3 + 30 * s**4) / RAMP,
                  (60 * s - 180 * s**2 + 120 * s**3) / RAMP**2)
    move = m.q - m.q[0]
    still = np.zeros((REST, 3))
    q = np.concatenate([np.repeat(m.q[:1], REST, axis=0), m.q[0] + w * move])
    qd = np.concatenate([still, dw * move + w * m.qd])
    qdd = np.concatenate([still, ddw * move + 2 * dw * m.qd + w * m.qdd])
    tau = LYNX.nominal.torque(q, qd, qdd) + np.asarray(OFFSETS[k])
    tau[:REST] += np.asarray(STATIC[k]) if static else 0.0
    tau += noise * np.random.default_rng(k).normal(size=tau.shape)
    return q, qd, qdd, tau


def test_the_rule_is_the_training_runs_pooled_residual_never_the_run_s_rest():
    """Noise-free runs of the model itself: a new run's offset is the closed form
    sum_k (n_k o_k + r_k s_k) / sum_k n_k over the training runs (offset o_k on all n_k
    samples, static friction s_k on their r_k at rest), whatever the scored run's own rest
    or offset; a tail's is its own run's trained part's."""
    train, held = [_run(0), _run(1)], _run(2)
    assert first_rest(held[1]) >= REST
    n = np.array([len(r[0]) for r in train])
    closed = (sum(n_k * np.asarray(o) + REST * np.asarray(s)
                  for n_k, o, s in zip(n, OFFSETS, STATIC, strict=False)) / n.sum())
    model = LYNX.nominal
    np.testing.assert_allclose(held_out_offset(model, train), closed, atol=1e-12)
    scored = whole_run(held, train)
    np.testing.assert_allclose(scored.offset(model), closed, atol=1e-12)
    # the rest reads offset + static friction: not what the rule takes
    np.testing.assert_allclose(residual_offset(model, tuple(a[:REST] for a in held)),
                               np.add(OFFSETS[2], STATIC[2]), atol=1e-12)
    expected = rel_error(model.torque(*held[:3]) + closed, held[3])
    np.testing.assert_allclose(scored_error(model, [scored]), expected, rtol=1e-12)
    # a tail continues its run: that run's offset on its trained part (its rest included)
    cut = 300
    tail = run_tail(tuple(a[:cut] for a in held), tuple(a[cut:] for a in held))
    own = (cut * np.asarray(OFFSETS[2]) + REST * np.asarray(STATIC[2])) / cut
    np.testing.assert_allclose(tail.offset(model), own, atol=1e-12)


def test_identify_s_held_out_runs_by_the_rule():
    """identify's split: a run the holdout cuts continues its trained part (the same run), a
    run wholly held out takes every training run's samples."""
    runs = [_run(0), _run(1), _run(2)]
    samples = tuple(np.concatenate([r[i] for r in runs]) for i in range(4))
    labels = np.repeat([0, 1, 2], [len(r[0]) for r in runs])
    n_train = len(runs[0][0]) + 100  # the second run cut after its first 100 samples
    trained, scored = split_runs(samples, n_train, labels)
    assert [len(r[0]) for r in trained] == [len(runs[0][0]), 100]
    assert [s.to_json()["offset_rule"] for s in scored] == ["same run", "training runs"]
    model = LYNX.nominal
    np.testing.assert_allclose(scored[0].offset(model),
                               residual_offset(model, tuple(a[:100] for a in runs[1])))
    np.testing.assert_allclose(scored[1].offset(model), held_out_offset(model, trained))


def _write(path, run: tuple) -> str:
    t = np.arange(len(run[0])) * 0.01
    np.savez(path, t=t, q=run[0], qd=run[1], qdd=run[2], tau=run[3],
             meta=np.array(json.dumps({"robot": "lynxmotion"})))
    return str(path)


@pytest.fixture(scope="module")
def commands(tmp_path_factory):
    """identify --validate, closeloop --validate (declaring identify's model) and predict
    (with either model) on the same held-out run. No static friction at the rests here: its
    end, as the motion starts, is a transient closeloop leaves out as an external torque
    (identification.closeloop.events), where identify keeps every sample."""
    tmp = tmp_path_factory.mktemp("offset_rule")
    a, b, c = (_write(tmp / f"{n}.npz", _run(k, noise=0.002, static=False))
               for k, n in enumerate("abc"))
    model = tmp / "MODEL.json"
    assert main(["identify", "--data", f"{a},{b}", "--validate", c, "--out", str(model)]) == 0
    assert main(["closeloop", "--data", f"{a},{b}", "--validate", c, "--declared", str(model),
                 "--out", str(tmp / "cl")]) == 0
    predicted = {}
    for name, spec in (("identify", model), ("closeloop", tmp / "cl" / "model.json")):
        out = tmp / f"{name}.npz"
        assert main(["predict", "--model", str(spec), "--data", c, "--out", str(out)]) == 0
        predicted[name] = dict(np.load(out))
    return (json.loads(model.read_text()), json.loads((tmp / "cl" / "closeloop.json").read_text()),
            json.loads((tmp / "cl" / "model.json").read_text()), predicted)


def test_the_three_commands_score_a_held_out_run_with_the_same_offset(commands):
    """The held-out run's offset identify scored with is the one predict adds with identify's
    model; closeloop scores the same model (its declared one, 'before') with the same error,
    and predict with closeloop's model reproduces its offset and error after."""
    identified, loop, loop_model, predicted = commands
    offset = identified["sensor_offsets"]["heldout"][0]
    assert identified["metrics"]["heldout_runs"][0]["offset"] == offset
    assert identified["metrics"]["heldout_runs"][0]["offset_rule"] == "training runs"
    np.testing.assert_allclose(identified["sensor_offsets"]["new_run"], offset, atol=1e-12)
    np.testing.assert_allclose(predicted["identify"]["offset"][0], offset, atol=1e-12)
    errors = identified["metrics"]["heldout_rel_rmse"]
    np.testing.assert_allclose(predicted["identify"]["rel_error"], errors, rtol=1e-9)
    np.testing.assert_allclose(loop["error_before"], errors, rtol=1e-9)
    assert loop["heldout_runs"][0]["offset_rule"] == "training runs"
    np.testing.assert_allclose(predicted["closeloop"]["offset"][0],
                               loop["heldout_sensor_offsets"][0], atol=1e-12)
    np.testing.assert_allclose(loop_model["sensor_offsets"]["new_run"],
                               loop["heldout_sensor_offsets"][0], atol=1e-12)
    np.testing.assert_allclose(predicted["closeloop"]["rel_error"], loop["error_after"],
                               rtol=1e-9)
    # the training runs' offsets, not the held-out run's own (0.09, -0.03, 0.02) its rest reads
    assert offset[0] == pytest.approx(np.mean([o[0] for o in OFFSETS[:2]]), abs=0.005)
    assert abs(offset[0] - OFFSETS[2][0]) > 0.05
