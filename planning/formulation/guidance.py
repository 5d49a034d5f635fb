"""Linear guidance (de Groot, Ferranti, Gavrila & Alonso-Mora, IEEE T-RO 2024): a re-plan of
a class's plan held in its class. At each obstacle slot of the re-plan, each link that comes
near is given the direction from the obstacle's centre to its nearest point on the plan it
re-plans from; its clearance row then measures the link's offset along that direction, not
its distance (planning.formulation.clearance.guided_link_clearances). The offset is at most the
distance, so a guided plan that keeps its rows keeps the threshold, and its links stay on the
sides of the obstacle they passed on: the class (planning.bank.classes) cannot flip within a
re-plan. Normals are taken afresh from each re-plan's start, so a class's plan may still slide
round the obstacle from one sample to the next."""

from __future__ import annotations

import numpy as np

from planning.formulation.clearance import link_offsets
from planning.formulation.kinematics import ArmGeometry


def normals(geometry: ArmGeometry, trajectory, times: np.ndarray, centres: np.ndarray,
            slots: int, near: float) -> np.ndarray:
    """The guidance parameters of the elastic NLP (planning.formulation.nlp, its `guide`: 3
    per link and slot, slot-major) for obstacle samples at `times` (the slots in use, in
    order) with `centres` (m), read off `trajectory` (the plan re-planned from): the unit
    direction from each centre to each link's nearest point where the link comes within
    `near` of the obstacle (m, its clearance), zero elsewhere (the row unguided)."""
    guide = np.zeros((slots, len(geometry.links), 3))
    if len(times):
        offset = link_offsets(geometry, trajectory.position(np.asarray(times, float)),
                              np.asarray(centres, float))
        distance = np.linalg.norm(offset, axis=-1)
        clearance = distance - geometry.link_radii if geometry.radii else distance
        guided = (clearance < near) & (distance > 1e-9)
        guide[: len(times)][guided] = offset[guided] / distance[guided][:, None]
    return guide.ravel()
