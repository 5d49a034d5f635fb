"""Which obstacle samples a solve must see: the ones that can come within the threshold.

The NLP has a fixed number of obstacle slots (a small number keeps each IPOPT
iteration cheap). Samples whose clearance on a reference trajectory is far above
the threshold contribute nothing to the penalty; the rest fill the slots (evenly
thinned when there are more of them than slots). The solver re-screens on its
own solution until the chosen set stops changing.
"""

from __future__ import annotations

import numpy as np

from planning.clearance import link_clearances
from planning.kinematics import ArmGeometry
from planning.solver import ObstacleForecast
from planning.trajectory import PolynomialTrajectory


def screen(forecast: ObstacleForecast, reference: PolynomialTrajectory, geometry: ArmGeometry,
           threshold: float, slots: int, margin: float = 0.03) -> ObstacleForecast:
    """The samples in (t_begin, t_end] whose reference clearance is below threshold + margin."""
    times = np.asarray(forecast.times)
    inside = np.flatnonzero((times > reference.t_begin + 1e-12)
                            & (times <= reference.t_end + 1e-12))
    q = reference.position(times[inside])
    clearance = link_clearances(geometry, q, forecast.centres[inside]).min(axis=1)
    near = inside[clearance < threshold + margin]
    if len(near) > slots:
        near = near[np.round(np.linspace(0, len(near) - 1, slots)).astype(int)]
    return ObstacleForecast(times[near], forecast.centres[near])
