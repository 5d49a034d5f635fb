"""The dataset contract: one experiment's time series, and its .npz file.

`generate` writes, `ingest` will write, and `identify`, `predict` and `closeloop`
read the same file: keys `t, q, qd, qdd, tau` (what a user measures), `tau_clean`
(noise-free torque, where known) and `meta` (a JSON string). Arrays are
(samples, dof) in SI units: s, rad, rad/s, rad/s^2, N m.
"""

from __future__ import annotations

import json
import tokenize
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from harness.errors import UserError
from identification.torque_model import Motion

STATE_KEYS = ("q", "qd", "qdd")
MAX_DOF = 64
# Magnitudes no arm reaches: a file beyond them is corrupt or in other units (deg, mrad, ...).
MAGNITUDE = {"t": (1e7, "s"), "q": (1e3, "rad"), "qd": (1e4, "rad/s"), "qdd": (1e6, "rad/s^2"),
             "tau": (1e6, "N m")}


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


def _read_npz(path: Path, keys, optional) -> tuple[dict[str, np.ndarray], object]:
    """The raw arrays named by keys (required) and optional, and the raw meta array."""
    if not path.is_file():
        raise UserError(f"data file not found: {path}")
    if not zipfile.is_zipfile(path):
        raise UserError(f"{path}: not an .npz archive" + (" (empty file)" if not path.stat().st_size
                                                           else ""))
    try:
        with np.load(path, allow_pickle=False) as npz:
            missing = [k for k in keys if k not in npz.files]
            if missing == ["tau"] and "current" in npz.files:  # ingest --gains-unknown
                raise UserError(f"{path} holds motor currents (A) with unknown drive gains, not "
                                "torque: ingest it with --current-gains K1,...,Kn, or identify "
                                "the gains with identify --loaded L.npz --load-mass KG")
            if missing:
                found = ", ".join(npz.files) or "none"
                raise UserError(f"{path}: missing keys {', '.join(missing)} (found: {found})")
            present = [*keys, *(k for k in optional if k in npz.files)]
            raw = {k: npz[k] for k in present}
            meta = npz["meta"] if "meta" in npz.files else None
    except UserError:
        raise
    # what a truncated or corrupted archive raises: the zip layer, the .npy header, short reads
    except (zipfile.BadZipFile, zlib.error, ValueError, EOFError, OSError, KeyError,
            UnicodeDecodeError, SyntaxError, tokenize.TokenError) as exc:  # .npy header parse
        detail = " ".join(str(exc).split()) or type(exc).__name__
        raise UserError(f"{path}: not a readable .npz ({detail})") from None
    return raw, meta


def _as_real(path: Path, key: str, x: np.ndarray) -> np.ndarray:
    """x as a float array; UserError unless it holds real numbers (bool, int or float)."""
    if x.dtype.kind not in "iuf":
        raise UserError(f"{path}: '{key}' must hold real numbers, got dtype {x.dtype}")
    return x.astype(float)


def _meta(path: Path, raw) -> dict:
    """The meta dict from the archive's 'meta' entry (a JSON string); {} when absent."""
    if raw is None:
        return {}
    if raw.dtype.kind not in "US" or raw.ndim != 0:
        raise UserError(f"{path}: 'meta' must be a JSON string, got {raw.dtype} {raw.shape}")
    try:
        meta = json.loads(str(raw))
    except ValueError:
        raise UserError(f"{path}: 'meta' is not valid JSON") from None
    if not isinstance(meta, dict):
        raise UserError(f"{path}: 'meta' must be a JSON object, got {type(meta).__name__}")
    return meta


def load_arrays(path: str | Path, keys=STATE_KEYS, optional=()) -> tuple[dict[str, np.ndarray], dict]:
    """The arrays named by keys (required) and optional (where present), each (n, dof) with
    n >= 1 and 1 <= dof <= MAX_DOF, real, finite, within MAGNITUDE, of one shape, and the meta
    dict; UserError naming the problem otherwise (empty, truncated or corrupted file, ...)."""
    path = Path(path)
    raw, raw_meta = _read_npz(path, keys, optional)
    arrays = {k: _as_real(path, k, x) for k, x in raw.items()}
    check_arrays(path, arrays)
    return arrays, _meta(path, raw_meta)


def check_arrays(source, arrays: dict[str, np.ndarray]) -> None:
    """UserError (naming source) unless every array is (n, dof) with n >= 1 and
    1 <= dof <= MAX_DOF, finite, within MAGNITUDE, all of one shape; `t` may be (n,)."""
    path = source
    arrays = {k: (x[:, None] if k == "t" and x.ndim == 1 else x) for k, x in arrays.items()}
    for k, x in arrays.items():
        if x.ndim != 2:
            raise UserError(f"{path}: '{k}' must be 2-D (samples, dof), got shape {x.shape}")
        if x.shape[0] == 0 or not 1 <= x.shape[1] <= MAX_DOF:
            raise UserError(f"{path}: '{k}' has shape {x.shape}: needs >= 1 sample and 1 to "
                            f"{MAX_DOF} joints")
        if not np.all(np.isfinite(x)):
            raise UserError(f"{path}: '{k}' contains NaN or inf")
        bound = MAGNITUDE.get(k.removesuffix("_clean"))
        if bound is not None and np.abs(x).max() > bound[0]:
            raise UserError(f"{path}: '{k}' reaches {np.abs(x).max():.3g} {bound[1]}, beyond "
                            f"any arm's ({bound[0]:g} {bound[1]})")
    if len({x.shape for k, x in arrays.items() if k != "t"}) > 1:
        shapes = ", ".join(f"{k} {x.shape}" for k, x in arrays.items())
        raise UserError(f"{path}: shape mismatch between arrays: {shapes}")
