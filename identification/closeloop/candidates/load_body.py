"""The body a load rides on, chosen by the data: the payload candidate fitted on each candidate
body near the chain's end (harness.robots.bodies.candidate_bodies) and scored by held-out
validation (leave one run out, or contiguous blocks of one run); the body whose payload
predicts the held-out samples best carries it. No rule on a joint's name: on
example-robot-data's finger_edu, whose joints are all named finger_..., the gripper rule put a
0.02 kg load on the wrong link and read it as 277 kg.
"""

from __future__ import annotations

import numpy as np

from identification.closeloop.candidates.payload import LastBody, payload_column
from identification.closeloop.selection.crossval import BlockValidation


def choose_body(bodies: tuple[LastBody, ...], base, target, states, w, reach: float, folds,
                several: bool) -> tuple[LastBody, dict]:
    """The body among bodies whose payload (fitted on all the training samples, its centre of
    mass within reach m) leaves the least validation error power, and what each left, as a
    fraction of the validation error power without a payload."""
    without = float(np.sum(BlockValidation.build(
        base, target, np.zeros((*target.shape, 1)), w, folds, refit_offset=several).sse([])))
    scores = []
    for body in bodies:
        try:
            candidate = payload_column(base, target, body(*states), w, reach)
        except ValueError:  # the conic fit failed on this body: it carries no candidate
            candidate = None
        if candidate is None:
            scores.append(without)
            continue
        cv = BlockValidation.build(base, target, candidate[0][:, :, None], w, folds,
                                   refit_offset=several)
        scores.append(float(np.sum(cv.sse([0]))))
    order = np.argsort(scores)
    best = int(order[0])
    ratio = [s / max(without, 1e-300) for s in scores]
    report = {"chosen": bodies[best].name,
              "candidates": [{"body": b.name, "validation_power": r}
                             for b, r in zip(bodies, ratio, strict=True)],
              "rule": "the payload fitted on each body near the chain's end, validated as the "
                      "effects are; validation_power: the held-out error power left, as a "
                      "fraction of that without a payload"}
    if len(bodies) > 1:
        report["next"] = bodies[int(order[1])].name
        report["margin"] = scores[int(order[1])] / max(scores[best], 1e-300) - 1.0
    return bodies[best], report
