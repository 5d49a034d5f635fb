"""Result files are complete or absent: write to a temporary file, then rename."""

from __future__ import annotations

import json
import os
import secrets
from collections.abc import Callable
from pathlib import Path

import numpy as np

from harness import interrupt
from harness.errors import UserError


def atomic_write(path: str | Path, write: Callable[[str], None], suffix: str = "") -> None:
    """Call write(tmp_path) and move the finished file to path; nothing is left on failure."""
    path = Path(path)
    if path.is_dir():
        raise UserError(f"output path {path} is a directory, expected a file name")
    output_dir(path.parent)
    # the temporary's name is known before the file exists, so an interrupt at any instant
    # after its creation (even inside the call that creates it) finds it and removes it
    tmp = str(path.parent / f".{path.name}.{secrets.token_hex(8)}{suffix}")
    try:
        try:
            os.close(os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
        except OSError as exc:
            raise UserError(f"cannot write to {path.parent}: {exc.strerror}") from None
        write(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # created 0600; results are ordinary files
        interrupt.check()  # no new result after Ctrl-C, even one a library swallowed
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def output_dir(path: str | Path) -> Path:
    """Create the folder path (and parents); UserError if a file stands in the way."""
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        raise UserError(f"cannot create output folder {path}: a file of that name exists") from None
    except OSError as exc:
        raise UserError(f"cannot create output folder {path}: {exc.strerror}") from None
    return path


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


def read_json(path: str | Path, what: str) -> dict:
    """The JSON object in the file path (`what` names it in errors: "model", "plan");
    UserError on a missing, unreadable, empty or malformed file and on anything but an object
    at the top level. NaN/Infinity parse: the caller's validation names the field holding one."""
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{what} file not found: {path}")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise UserError(f"{what} file {path} is not UTF-8 text") from None
    except OSError as exc:
        raise UserError(f"cannot read {what} file {path}: {exc.strerror}") from None
    if not text.strip():
        raise UserError(f"{what} file {path} is empty")
    try:
        payload = json.loads(text)
    except ValueError as exc:  # JSONDecodeError, or an integer too long to convert
        raise UserError(f"{what} file {path} is not valid JSON: {exc}") from None
    except RecursionError:
        raise UserError(f"{what} file {path} is nested too deeply") from None
    if not isinstance(payload, dict):
        raise UserError(f"{what} file {path} must hold a JSON object, not {type(payload).__name__}")
    return payload


def write_json(path: str | Path, payload: dict) -> None:
    """Write payload as indented JSON atomically (numpy arrays become lists)."""

    def write(tmp: str) -> None:
        with open(tmp, "w") as f:
            json.dump(payload, f, indent=2, default=_jsonable, allow_nan=False)
            f.write("\n")

    atomic_write(path, write)


def write_text(path: str | Path, text: str) -> None:
    """Write text to path atomically."""
    atomic_write(path, lambda tmp: Path(tmp).write_text(text))


def write_npz(path: str | Path, **arrays) -> None:
    """Write arrays to an .npz atomically (np.savez appends .npz unless the name has it)."""
    atomic_write(path, lambda tmp: np.savez(tmp, **arrays), suffix=".npz")
