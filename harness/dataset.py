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
    try:
        with np.load(path, allow_pickle=False) as npz:
            missing = [k for k in keys if k not in npz.files]
            if missing:
                raise UserError(f"{path}: missing keys {', '.join(missing)}")
            arrays = {k: np.asarray(npz[k], dtype=float) for k in keys}
            meta = json.loads(str(npz["meta"])) if "meta" in npz.files else {}
    except (zipfile.BadZipFile, ValueError, OSError) as exc:
        raise UserError(f"{path}: not a readable .npz ({exc})") from None
    shape = arrays[keys[0]].shape
    for k, x in arrays.items():
        if x.ndim != 2 or x.shape != shape:
            raise UserError(f"{path}: '{k}' has shape {x.shape}, expected {shape} (n, dof)")
        if not np.all(np.isfinite(x)):
            raise UserError(f"{path}: '{k}' contains NaN or inf")
    return arrays, meta
