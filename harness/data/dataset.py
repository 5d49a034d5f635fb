"""Read and validate a dataset .npz written by `torquebench generate` (or by a user)."""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np

from harness.errors import UserError

STATE_KEYS = ("q", "qd", "qdd")


def load_states(path: str | Path, keys=STATE_KEYS) -> tuple[dict[str, np.ndarray], dict]:
    """Arrays named by keys (each (n, dof), finite, same shape) and the meta dict."""
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
            arrays = {k: np.asarray(npz[k], dtype=float) for k in keys}
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
        raise UserError(f"{path}: arrays differ in shape: {shapes}")
    return arrays, meta
