"""Long studies, run on demand: `torquebench study NAME --out DIR` (or `bench --full`).

Each is a module (for a package, its `section` module) with `run(context) -> SectionResult`
like a bench section, and a one-line description here: harness.studies.<name>, or the module
MODULES names (the paper's studies live in harness.paper, imported only when run). A study
reports what it measures as results, checks and targets; it is smoke-tested in
tests/test_studies.py on its quick form.
"""

from __future__ import annotations

from harness.bench import entry_module

STUDIES = {
    "paper_identification": "the paper's identification study on its arm: noise levels, "
                            "robustness over noise draws, denoising, pysindy peers",
    "paper_planning": "the paper's planning study: minimum jerk, parametrizations against dense "
                      "quadrature, the swaying obstacle, solver timings",
    "realtime": "Algorithm 2 on 20 random obstacle scenarios: re-plan CPU times, deadline "
                "misses, executed energy and clearance, per planner",
    "generalization": "identification on data along another excitation than the project's, "
                      "a perturbed URDF prior, judged on a fresh motion against the oracle "
                      "(UR5, Panda, xArm7, Z1)",
    "prior_tie": "the consistent fit's prior-weight margin (TIE) chosen on draws no bench "
                 "section scores and re-scored on fresh ones (UR5, xArm7, SO-101)",
    "outside_default": "identify's defaults on data made outside its own path (multisines "
                       "and a Fourier series of other harmonics, 5 and 10 % noise), fresh "
                       "draws, judged on fresh motions against the oracle",
    "identification_draws": "identification over many fresh draws of data the project did "
                            "not design (2, 5 and 10 % noise; Lynxmotion: default, held to "
                            "the rigid body or not, --library kinematic; UR5): per joint the "
                            "ratio to the oracle, median and worst, what the selection "
                            "dropped and cost",
    "prior_metric": "the consistent fit's prior metric, ridge against entropic, under a "
                    "perturbed URDF prior and the URDF as truth, on fresh draws (Lynxmotion, "
                    "UR5, Kinova)",
    "first_plan": "the first plan on a new 7-DOF robot (Panda), compilation included, the "
                  "second run's, a --realtime first plan's, and the same plan from the quick "
                  "and the optimized build",
    "bank": "the bank of plans (plan's default re-planner) on fresh random scenarios (seed "
            "9784, 20 Lynxmotion, 5 UR5, 5 Panda) against one plan re-planned and the "
            "penalty loop: executed energy, clearance, re-plan CPU",
    "drive_gains": "motor drive gains identified with the dynamics (identify --loaded "
                   "--load-mass) on simulated logs of currents: UR5 and Panda, unloaded and "
                   "loaded runs, 5 % noise, each gain's error (target 3 %)",
    "parameter_intervals": "identify's printed 95 % intervals on the identified parameters "
                           "(base parameters, the bodies the data determine) against the truth "
                           "over 20 fresh draws with a spring the model lacks (Lynxmotion, UR5; "
                           "sparse and consistent fits): how often they cover it",
    "payload": "the load a robot carries named by closeloop --data: UR5 and Panda plants with a "
               "load on the flange, with and without friction that grows with the load, and "
               "without a load (mass 3 %, centre of mass 1 cm)",
    "pushes": "the world pushing a robot: Lynxmotion, UR5 and Panda plants pushed "
              "three times a run on fresh draws, alone and beside a load and viscous friction: "
              "pushes found, false events per minute, onset errors, the load and the friction "
              "named with the pushes against without",
    "offset_rule": "the sensor offset a held-out run is scored with: "
                   "training runs', first rest's, none, both rests, a blend and the rule the "
                   "commands use, against the true offset on simulated UR5 and Panda runs with "
                   "static friction at rest, and on the real Panda log cut into runs",
    "replan_profile": "an anytime-SQP iteration and a warm re-plan cut into their parts (the "
                      "compiled evaluation, the QP's build, DAQP, the merit, the checks, the "
                      "Python around them) on the Lynxmotion's and the README's UR5 scenarios",
    "realtime_runs": "plan --realtime run 20 times on each of 5 fresh Lynxmotion scenarios, "
                     "quiet and under a load the study makes (a busy loop per core): runs "
                     "refused, each run's smallest clearance, the executed energy's spread",
    "sysid_peer": "MuJoCo's system-identification toolbox (mujoco.sysid, its rollout residual, "
                  "a wall-time budget) beside identify on the real Panda log's held-out part: "
                  "torque error, rollout error at 0.1 and 0.5 s, bodies' consistency, fit time",
    "closeloop_plants": "closing the loop on the Lynxmotion's hand-written plants, with both "
                        "declared models (Pinocchio and the identified one)",
}

# studies that live outside this package: name -> their module
MODULES = {"paper_identification": "harness.paper.studies.paper_identification",
           "paper_planning": "harness.paper.studies.paper_planning"}


def load_study(name: str):
    """The entry module of study name."""
    return entry_module("studies", name, STUDIES, MODULES.get(name, f"harness.studies.{name}"))
