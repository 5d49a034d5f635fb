"""Which obstacle samples a solve must see: the ones that can come within the threshold.

The NLP has a fixed number of obstacle slots (a small number keeps each IPOPT
iteration cheap). Samples whose clearance on a reference trajectory is far above
the threshold contribute nothing to the penalty; the rest fill the slots (evenly
thinned when there are more of them than slots). The solver re-screens on its
own solution until the chosen set stops changing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planning.clearance import link_clearances
from planning.kinematics import ArmGeometry
from planning.solver import ObstacleForecast
from planning.trajectory import PolynomialTrajectory


@dataclass(frozen=True)
class Screen:
    """What a reference motion says about a forecast: the samples a solve must see
    (subset), the times where the reference dips below the threshold (dips), and the
    largest gap (s) between subset samples when the near ones were thinned to fit the
    slots (0: not thinned, every near sample is in the subset)."""

    subset: ObstacleForecast
    dips: np.ndarray
    gap: float
    lowest: float  # the reference's smallest clearance over the samples (m; inf: none)

    def covered(self, chosen: np.ndarray) -> bool:
        """True if a solve that saw the samples at `chosen` times saw every dip: each one,
        or (thinned) a chosen sample within the gap of it. A sample the solve did not see,
        above the threshold on its result, adds a zero penalty term with a zero gradient:
        the result is optimal with it too."""
        distance = np.abs(np.asarray(self.dips)[:, None] - np.asarray(chosen)[None, :])
        return bool(np.all(distance.min(axis=1, initial=np.inf) <= self.gap + 1e-9))


def screen(forecast: ObstacleForecast, reference: PolynomialTrajectory, geometry: ArmGeometry,
           threshold: float, slots: int, margin: float = 0.03) -> Screen:
    """The samples in (t_begin, t_end] whose reference clearance is below threshold + margin
    (evenly thinned to `slots`), and those below the threshold."""
    times = np.asarray(forecast.times)
    inside = np.flatnonzero((times > reference.t_begin + 1e-12)
                            & (times <= reference.t_end + 1e-12))
    q = reference.position(times[inside])
    clearance = link_clearances(geometry, q, forecast.centres[inside]).min(axis=1)
    near, gap = inside[clearance < threshold + margin], 0.0
    if len(near) > slots:
        near = near[np.round(np.linspace(0, len(near) - 1, slots)).astype(int)]
        gap = float(np.max(np.diff(times[near])))
    return Screen(ObstacleForecast(times[near], forecast.centres[near]),
                  times[inside[clearance < threshold]], gap,
                  float(np.min(clearance, initial=np.inf)))
