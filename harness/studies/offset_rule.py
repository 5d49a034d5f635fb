"""Study `offset_rule`: which sensor offset a held-out run is scored with.

A run's torque sensor is re-zeroed between runs: its offset changes. A run at rest reads
gravity + offset + the static friction holding each joint, anywhere in [-Fs, Fs]: the rest's
reading is not the offset where the band is wide against the offset's change. Candidates
for the held-out run's offset, each scored by the held-out error (identification.metrics.
rel_error against the measured torque, on the run's motion after its first rest) against
the oracle's (the true offset):

- training (the rule): the model's mean residual on the training runs' samples
  (identification.closeloop.closed.offsets.held_out_offset, what identify, closeloop and predict
  score with);
- rest: the run's first rest's reading (the model's mean residual there);
- none: 0;
- both rests: the first and the last rest's readings averaged (a run that ends at rest);
- choice: per joint the rest where the training runs' own rests read their offsets closer
  (RMS) than those offsets agree with one another (sample variance x (1 + 1/runs)), else
  training;
- blend: rest and training weighed by the inverse of those two squared errors;
- training, one run: the first training run's offset alone (the same fit).

Simulated (UR5, Panda; quick: the UR5, fewer draws and samples): per draw, three runs of
`sines_motion` (random sums of sines; mj_inverse on the plant) each between two rests of
REST samples, with one friction law per draw (viscous, Coulomb, and at a rest a static
friction drawn in [-Fs, Fs], Fs = Coulomb x [1, 1.5]; Coulomb COULOMB of the arm's median
joint torque std, so that it is wide on the low-torque joints, as on a real arm), each run's
offset drawn (OFFSET of each joint's torque std, a new draw each run) and white noise (NOISE).
Two runs train `identify`'s consistent fit (a prior pulled toward a perturbed URDF, an
offset per run); the third is scored, under that fit and under the perturbed URDF itself
(the model closeloop declares). Seeds SEED (draw d: [SEED, arm, d]), drawn once and
nothing chosen on them.

Real (data/panda_gaz2019, one sensor throughout: its offset did not change): the log at its
own rate (1 kHz) cut into PIECES runs after its first rest, each run the log's rest followed
by its piece (the rest this sensor shows, read before every piece); each piece scored by the
identify fit on the others (every 10th sample) and by the URDF, against the best constant
(the mean residual on the scored samples: a bound no rule can reach).
"""

from __future__ import annotations

import numpy as np

from data import DATA
from harness.data.generate import inverse_torques
from harness.data.ingest import ingest
from harness.identify.fits import arm_identification
from harness.identify.scoring import perturbed_nominal, sines_motion
from harness.report.results import Context, SectionResult, Target, check
from harness.robots.arm import Arm
from identification.closeloop.closed.offsets import first_rest, held_out_offset, residual_offset
from identification.identify import identify
from identification.kinematic_model import KinematicModel
from identification.metrics import rel_error
from identification.regression.consistent import ConsistentRegressor

# drawn once (numpy.random.default_rng().integers(10_000)) and written here; nothing in the
# rule or the simulation was chosen on it
SEED = 573
DRAWS, QUICK_DRAWS = 8, 2
SAMPLES, QUICK_SAMPLES = 1600, 800  # motion samples a run, at 200 Hz
REST = 100  # samples (0.5 s) at rest before and after each run's motion
NOISE = 0.02  # white torque noise, of each joint's torque std
OFFSET = 0.03  # each run's sensor offset: normal, this of each joint's torque std
COULOMB = (0.03, 0.15)  # each joint's Coulomb friction: uniform, of the median joint's std
VISCOUS = (0.01, 0.05)  # N m s/rad, of the joint's torque std
BREAKAWAY = (1.0, 1.5)  # the static band Fs against the Coulomb level
REST_WIDTH = 0.01  # rad/s: the Coulomb friction's tanh width in motion
PIECES = 4  # the real log's runs
RULES = ("training (the rule)", "rest", "none", "both rests", "blend", "choice")


def _at_rest(arm: Arm, q: np.ndarray, count: int) -> tuple:
    """count samples held at posture q: states and the torque holding them (gravity)."""
    q = np.repeat(q[None], count, axis=0)
    zero = np.zeros_like(q)
    return q, zero, zero, inverse_torques(arm.mujoco, q, zero, zero)


def _friction(arm: Arm, rng, spread: np.ndarray) -> dict:
    """One friction law per draw (levels in N m)."""
    dof = arm.dof
    coulomb = np.median(spread) * rng.uniform(*COULOMB, dof)
    return {"viscous": spread * rng.uniform(*VISCOUS, dof), "coulomb": coulomb,
            "static": coulomb * rng.uniform(*BREAKAWAY, dof)}


def simulated_run(arm: Arm, seed: int, samples: int, law: dict | None, rng, spread=None):
    """A run between two rests: (q, qd, qdd, tau), its true offset, its rests' static
    friction; law None: drawn here from the motion's spread (returned)."""
    m = sines_motion(arm, samples, seed)
    spread = m.tau_clean.std(axis=0) if spread is None else spread
    law = _friction(arm, rng, spread) if law is None else law
    start, end = _at_rest(arm, m.q[0], REST), _at_rest(arm, m.q[-1], REST)
    static = [law["static"] * rng.uniform(-1.0, 1.0, arm.dof) for _ in range(2)]
    moving = (m.tau_clean + law["viscous"] * m.qd
              + law["coulomb"] * np.tanh(m.qd / REST_WIDTH))
    q, qd, qdd = (np.concatenate([start[i], getattr(m, k), end[i]])
                  for i, k in enumerate(("q", "qd", "qdd")))
    truth = np.concatenate([start[3] + static[0], moving, end[3] + static[1]])
    offset = OFFSET * spread * rng.normal(size=arm.dof)
    tau = truth + offset + NOISE * spread * rng.normal(size=truth.shape)
    return (q, qd, qdd, tau), offset, law, spread


def _last_rest(qd: np.ndarray) -> int:
    """Samples at the run's end after its last motion (0 if none)."""
    return first_rest(qd[::-1])


def _rest_reading(model, run: tuple) -> np.ndarray | None:
    """The model's mean residual on run's first rest (None without one)."""
    head = first_rest(run[1])
    return residual_offset(model, tuple(a[:head] for a in run)) if head else None


def evidence(model, train: list[tuple]) -> tuple[np.ndarray, np.ndarray]:
    """What the training runs say of a rest and of their offsets: (dof,) RMS of their rests'
    readings less their offsets (NaN with no rest), and (dof,) the expected RMS error of
    carrying their mean offset to a new run (sample variance x (1 + 1/runs); NaN with one)."""
    offsets = np.array([residual_offset(model, r) for r in train])
    rests = [(_rest_reading(model, r), o) for r, o in zip(train, offsets, strict=True)]
    misread = np.array([r - o for r, o in rests if r is not None])
    rest = (np.sqrt(np.mean(misread ** 2, axis=0)) if len(misread)
            else np.full(model.dof, np.nan))
    carry = (np.sqrt(np.var(offsets, axis=0, ddof=1) * (1 + 1 / len(train))) if len(train) > 1
             else np.full(model.dof, np.nan))
    return rest, carry


def candidates(model, train: list[tuple], run: tuple, oracle: np.ndarray | None) -> dict:
    """Each candidate's offset (dof,) for run under model, trained on train; oracle: the true
    offset (simulated) or None (real: the best constant on the scored samples)."""
    head, tail = first_rest(run[1]), _last_rest(run[1])
    moving = tuple(a[head:len(a) - tail] for a in run)
    carried = held_out_offset(model, train)  # the rule the commands use
    rest = _rest_reading(model, run)
    end = residual_offset(model, tuple(a[len(a) - tail:] for a in run)) if tail else rest
    rest_error, carry_error = evidence(model, train)
    with np.errstate(invalid="ignore"):
        take = rest_error < carry_error  # NaN: not told, the training runs'
    weight = np.nan_to_num(carry_error ** 2 / (rest_error ** 2 + carry_error ** 2))
    return {"offsets": {
        "training (the rule)": carried, "rest": rest, "none": np.zeros(model.dof),
        "both rests": 0.5 * (rest + end), "blend": weight * rest + (1 - weight) * carried,
        "choice": np.where(take, rest, carried),
        "training, one run": held_out_offset(model, train[:1]),
        "oracle": residual_offset(model, moving) if oracle is None else oracle},
        "scored": moving, "choice_takes_rest": take.tolist()}


def score(model, train, run, oracle=None) -> dict:
    """Each candidate's held-out error per joint and its excess over the oracle's."""
    c = candidates(model, train, run, oracle)
    q, qd, qdd, tau = c["scored"]
    torque = model.torque(q, qd, qdd)
    offsets = c["offsets"]
    errors = {k: rel_error(torque + o, tau) for k, o in offsets.items()}
    return {"error": {k: e.tolist() for k, e in errors.items()},
            "excess": {k: (e / errors["oracle"] - 1).tolist() for k, e in errors.items()},
            "offset": {k: np.asarray(o).tolist() for k, o in offsets.items()},
            "choice_takes_rest": c["choice_takes_rest"]}


def _models(arm: Arm, train: list[tuple], seed: int) -> dict:
    """identify's consistent fit (a prior toward a perturbed URDF, an offset per run) on the
    training runs, and that perturbed URDF."""
    nominal = perturbed_nominal(arm.nominal, seed)
    states = [np.concatenate([r[i] for r in train]) for i in range(4)]
    labels = np.repeat(np.arange(len(train)), [len(r[0]) for r in train])
    fit = identify(*states, arm.library, 0.0, regressor=ConsistentRegressor(
        nominal, ellipsoids=arm.ellipsoids), runs=labels).model
    urdf = KinematicModel(arm.library, arm.library.fold @ nominal, np.zeros(arm.dof), "nominal")
    return {"identified": fit, "perturbed URDF": urdf}


def simulated(name: str, index: int, draws: int, samples: int) -> list[dict]:
    arm = Arm.of(name)
    rows = []
    for d in range(draws):
        rng = np.random.default_rng([SEED, index, d])
        seeds = rng.integers(10_000, size=3)
        runs, law, spread = [], None, None
        for s in seeds:
            run, offset, law, spread = simulated_run(arm, int(s), samples, law, rng, spread)
            runs.append((run, offset))
        train, (held, offset) = [r for r, _ in runs[:2]], runs[2]
        models = _models(arm, train, int(seeds[0]))
        rows.append({"draw": d, "seeds": seeds.tolist(), "true_offset": offset.tolist(),
                     "static_band": law["static"].tolist(), "torque_std": spread.tolist(),
                     **{m: score(model, train, held, offset) for m, model in models.items()}})
    return rows


def real_log() -> list[dict]:
    """The shipped Panda log cut into PIECES runs, each scored by the others."""
    arm = Arm.of("panda")
    a = ingest(DATA / "panda_gaz2019" / "panda_gaz2019.csv.gz", arm).arrays
    log = tuple(a[k] for k in ("q", "qd", "qdd", "tau"))
    head = first_rest(log[1])
    cuts = np.linspace(head, len(log[0]), PIECES + 1).astype(int)
    runs = [tuple(np.concatenate([x[:head], x[lo:hi]]) for x in log)
            for lo, hi in zip(cuts[:-1], cuts[1:], strict=True)]
    _, regressor = arm_identification(arm, arm.dof, prior="nominal", measured=True)
    rows = []
    for h in range(PIECES):
        train = [r for k, r in enumerate(runs) if k != h]
        thin = [tuple(x[::10] for x in r) for r in train]
        states = [np.concatenate([r[i] for r in thin]) for i in range(4)]
        labels = np.repeat(np.arange(len(thin)), [len(r[0]) for r in thin])
        fit = identify(*states, arm.library, 0.0, regressor=regressor, runs=labels).model
        rows.append({"piece": h, "rest_samples": head, "samples": int(cuts[h + 1] - cuts[h]),
                     "identified": score(fit, train, runs[h]),
                     "URDF": score(arm.nominal, train, runs[h])})
    return rows


def summary(rows: list[dict], model: str) -> dict:
    """Per candidate: the excess over the oracle (%, median and 90th percentile over joints
    and draws) and the median over draws of the median joint's error."""
    out = {}
    for k in (*RULES, "training, one run", "oracle"):
        excess = np.array([r[model]["excess"][k] for r in rows])
        error = np.array([r[model]["error"][k] for r in rows])
        out[k] = {"excess_median": float(np.median(excess)),
                  "excess_p90": float(np.percentile(excess, 90)),
                  "excess_mean": float(np.mean(excess)),
                  "median_error": float(np.median(np.median(error, axis=1))),
                  "joint_excess_median": np.median(excess, axis=0).tolist()}
    return out


def _table(sums: dict) -> list[str]:
    md = ["| arm | model | offset | excess, median (%) | excess, 90th pct (%) | "
          "excess, mean (%) | median joint's error |", "|---|---|---|---|---|---|---|"]
    for (arm, model), s in sums.items():
        for k, v in s.items():
            md.append(f"| {arm} | {model} | {k} | {100 * v['excess_median']:.1f} | "
                      f"{100 * v['excess_p90']:.1f} | {100 * v['excess_mean']:.1f} | "
                      f"{v['median_error']:.3f} |")
    return md


def run(ctx: Context) -> SectionResult:
    names = ["ur5"] if ctx.quick else ["ur5", "panda"]
    draws = QUICK_DRAWS if ctx.quick else DRAWS
    samples = QUICK_SAMPLES if ctx.quick else SAMPLES
    sim = {name: simulated(name, i, draws, samples) for i, name in enumerate(names)}
    sums = {(name, m): summary(rows, m) for name, rows in sim.items()
            for m in ("identified", "perturbed URDF")}
    md = [f"Simulated: {draws} draws a robot (seed {SEED}, drawn once), runs of {samples} "
          f"samples between two rests of {REST}, offsets {OFFSET:.0%} of each joint's torque "
          f"std (a new draw each run), Coulomb {COULOMB[0]:.0%}-{COULOMB[1]:.0%} of the median "
          f"joint's std, static band x{BREAKAWAY[0]:g}-{BREAKAWAY[1]:g}, noise {NOISE:.0%}; two "
          "runs train, the third is scored. Held-out error's excess over the oracle's (true "
          "offset), over joints and draws:", ""]
    md += _table(sums)
    real = real_log()
    real_sums = {("panda (real log)", m): summary(real, m) for m in ("identified", "URDF")}
    md += ["", f"Real: data/panda_gaz2019 (one sensor, its offset unchanged) in {PIECES} runs, "
           "each scored by the fit on the others; excess over the best constant on the scored "
           "samples (a bound, fitted on them):", ""]
    md += _table(real_sums)
    rest_gap = np.array([np.subtract(r["identified"]["offset"]["rest"],
                                     r["identified"]["offset"]["oracle"]) for r in real])
    md += ["", "The real log's rest against each piece's best constant under the identify fit "
           "(N m, mean over pieces; the static friction holding the joints and the model's "
           "error at that posture): " + ", ".join(f"{x:+.2f}" for x in rest_gap.mean(axis=0))]
    results = {"seed": SEED, "draws": draws, "samples": samples, "rest": REST,
               "offset": OFFSET, "coulomb": COULOMB, "noise": NOISE,
               "simulated": {n: {"draws": rows, "summary": {m: sums[n, m] for m in
                                                          ("identified", "perturbed URDF")}}
                             for n, rows in sim.items()},
               "real": {"pieces": real, "summary": {m: real_sums["panda (real log)", m]
                                                    for m in ("identified", "URDF")},
                        "rest_minus_best_constant": rest_gap.mean(axis=0).tolist()}}
    allsums = {**sums, **real_sums}
    gaps = {f"{a} / {m}": s["training (the rule)"]["excess_mean"]
            - min(s[k]["excess_mean"] for k in RULES if k != "training (the rule)")
            for (a, m), s in allsums.items()}
    worst = max(gaps, key=gaps.get)
    results["rule_excess_above_best_other"] = gaps
    real_ratio = (real_sums["panda (real log)", "identified"]["training (the rule)"]["median_error"]
                  / real_sums["panda (real log)", "identified"]["oracle"]["median_error"])
    checks = [check("every_candidate_scored", all(np.isfinite(s[k]["excess_mean"])
                                                  for s in allsums.values() for k in RULES))]
    targets = [Target("offset rule: its mean excess over the oracle's error less the best other "
                      f"candidate's, worst case ({worst}; points of %)", 100 * gaps[worst], 0.0,
                      "%", note=f"seed {SEED}"),
               Target("offset rule on the real Panda log: the median joint's held-out error "
                      "against the best constant's (fitted on the scored samples)", real_ratio,
                      1.05, "x")]
    return SectionResult("\n".join(md), results, checks, targets)
