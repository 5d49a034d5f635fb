"""Result files are complete or absent: write to a temporary file, then rename."""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np


def atomic_write(path: str | Path, write: Callable[[str], None], suffix: str = "") -> None:
    """Call write(tmp_path) and move the finished file to path; nothing is left on failure."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=suffix)
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; results are ordinary files
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _jsonable(x):
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"not JSON serializable: {type(x).__name__}")


def write_json(path: str | Path, payload: dict) -> None:
    """Write payload as indented JSON atomically (numpy arrays become lists)."""

    def write(tmp: str) -> None:
        with open(tmp, "w") as f:
            json.dump(payload, f, indent=2, default=_jsonable, allow_nan=False)
            f.write("\n")

    atomic_write(path, write)


def write_npz(path: str | Path, **arrays) -> None:
    """Write arrays to an .npz atomically (np.savez appends .npz unless the name has it)."""
    atomic_write(path, lambda tmp: np.savez(tmp, **arrays), suffix=".npz")
