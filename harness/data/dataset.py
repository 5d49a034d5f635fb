"""The dataset contract: one experiment's time series, and its .npz file.

`generate` writes, `ingest` will write, and `identify`, `predict` and `closeloop`
read the same file: keys `t, q, qd, qdd, tau` (what a user measures), `tau_clean`
(noise-free torque, where known) and `meta` (a JSON string). Arrays are
(samples, dof) in SI units: s, rad, rad/s, rad/s^2, N m.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from harness.errors import UserError
from identification.torque_model import Motion

STATE_KEYS = ("q", "qd", "qdd")


@dataclass(frozen=True)
class Dataset(Motion):
    """Time series of one experiment: the motion, the torque measured and the clean one."""

    tau: np.ndarray
    tau_clean: np.ndarray
    meta: dict
    truth: dict = field(default_factory=dict)  # q/qd/qdd the simulator had (measured mode)

    def arrays(self) -> dict[str, np.ndarray]:
        """The npz payload of the CLI contract (plus true states where known)."""
        out = {k: getattr(self, k) for k in ("t", "q", "qd", "qdd", "tau", "tau_clean")}
        out.update({f"{k}_true": v for k, v in self.truth.items()})
        out["meta"] = np.array(json.dumps(self.meta))
        return out


def load_arrays(path: str | Path, keys=STATE_KEYS, optional=()) -> tuple[dict[str, np.ndarray], dict]:
    """The arrays named by keys (required) and optional (where present), each (n, dof),
    finite and of one shape, and the meta dict; UserError naming the problem otherwise."""
    path = Path(path)
    if not path.is_file():
        raise UserError(f"data file not found: {path}")
    if not zipfile.is_zipfile(path):
        raise UserError(f"{path}: not an .npz archive")
    try:
        with np.load(path, allow_pickle=False) as npz:
            missing = [k for k in keys if k not in npz.files]
            if missing:
                raise UserError(f"{path}: missing keys {', '.join(missing)}")
            present = [*keys, *(k for k in optional if k in npz.files)]
            arrays = {k: np.asarray(npz[k], dtype=float) for k in present}
            meta = json.loads(str(npz["meta"])) if "meta" in npz.files else {}
    except (zipfile.BadZipFile, ValueError, OSError) as exc:
        raise UserError(f"{path}: not a readable .npz ({exc})") from None
    for k, x in arrays.items():
        if x.ndim != 2:
            raise UserError(f"{path}: '{k}' must be 2-D (samples, dof), got shape {x.shape}")
        if not np.all(np.isfinite(x)):
            raise UserError(f"{path}: '{k}' contains NaN or inf")
    if len({x.shape for x in arrays.values()}) > 1:
        shapes = ", ".join(f"{k} {x.shape}" for k, x in arrays.items())
        raise UserError(f"{path}: shape mismatch between arrays: {shapes}")
    return arrays, meta
