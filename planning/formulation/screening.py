"""Which obstacle samples a solve must see: the ones that can come within the threshold.

The NLP has a fixed number of obstacle slots (a small number keeps each IPOPT
iteration cheap). Samples whose clearance on a reference trajectory is far above
the threshold contribute nothing to the penalty; the rest fill the slots (evenly
thinned when there are more of them than slots). The solver re-screens on its
own solution until the chosen set stops changing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from planning.formulation.clearance import link_clearances
from planning.formulation.kinematics import ArmGeometry
from planning.formulation.trajectory import PolynomialTrajectory
from planning.types import ObstacleForecast


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


MARGIN = 0.03  # m: samples this far above the threshold on the reference are screened in


def screen(forecast: ObstacleForecast, reference: PolynomialTrajectory, geometry: ArmGeometry,
           threshold: float, slots: int, margin: float = MARGIN) -> Screen:
    """The samples in (t_begin, t_end] whose reference clearance is below threshold + margin
    (evenly thinned to `slots`), and those below the threshold."""
    times = np.asarray(forecast.times)
    inside = np.flatnonzero((times > reference.t_begin + 1e-12)
                            & (times <= reference.t_end + 1e-12))
    q = reference.position(times[inside])
    clearance = link_clearances(geometry, q, forecast.centres[inside]).min(axis=1)
    near, gap = inside[clearance < threshold + margin], 0.0
    if len(near) > slots:
        near = near[_thinned(len(near), slots)]
        gap = float(np.max(np.diff(times[near])))
    return Screen(ObstacleForecast(times[near], forecast.centres[near]),
                  times[inside[clearance < threshold]], gap,
                  float(np.min(clearance, initial=np.inf)))


# The anytime SQP's screening (planning.anytime): the same rule, on clearances per sample and
# link that its compiled check already computed.

def on_horizon(forecast: ObstacleForecast | None, t_begin: float, duration: float):
    """The forecast's samples in (t_begin, t_begin + duration]: times (k,), centres (k, 3)."""
    if forecast is None:
        return np.zeros(0), np.zeros((0, 3))
    times = np.asarray(forecast.times, float)
    keep = (times > t_begin + 1e-12) & (times <= t_begin + duration + 1e-12)
    return times[keep], np.asarray(forecast.centres, float)[keep]


def near_samples(clearance: np.ndarray, threshold: float, slots: int) -> np.ndarray:
    """Indices of the samples whose clearance is within MARGIN of the threshold, evenly
    thinned to `slots`."""
    near = np.flatnonzero(clearance < threshold + MARGIN)
    if len(near) > slots:
        near = near[_thinned(len(near), slots)]
    return near


@numba.njit("i8[:](i8, i8)", cache=True, nogil=True)
def _thinned(count, slots):
    """`slots` of range(count) evenly: np.round(np.linspace(0, count - 1, slots)), the same
    floating-point steps and halves to even, in a loop
    (docs/realtime.md, 'planning.formulation.screening')."""
    out = np.empty(max(slots, 0), np.int64)
    step = (count - 1) / (slots - 1) if slots > 1 else 0.0
    for i in range(slots):
        out[i] = np.round(i * step)
    if slots > 1:
        out[slots - 1] = count - 1
    return out


def uncovered(dips: np.ndarray, slots: np.ndarray, rows: np.ndarray, count: int) -> bool:
    """True if a (sample, link) dip (dips: (k, links) booleans) was not seen by a solve with
    rows (slots, links) at the sample indices `slots`: as Screen.covered, when the near
    samples were thinned to `count` slots a dip within the largest gap between slots of one
    that has its link's row is covered."""
    slots = np.asarray(slots, np.int64)
    gap = int(np.max(np.diff(slots), initial=0)) if len(slots) == count else 0
    return _uncovered(np.asarray(dips, bool), slots, np.asarray(rows, bool), gap)


@numba.njit("(b1[:, :], i8[:], b1[:, :], i8)", cache=True, nogil=True)
def _uncovered(dips, slots, rows, gap):
    """uncovered's loop, compiled (numpy's argwhere and (dips, slots) masks took ~30 us)."""
    for i in range(dips.shape[0]):
        for link in range(dips.shape[1]):
            if not dips[i, link]:
                continue
            seen = False
            for j in range(len(slots)):
                if abs(slots[j] - i) <= gap and rows[j, link]:
                    seen = True
                    break
            if not seen:
                return True
    return False
