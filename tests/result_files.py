"""Is every result file in a folder complete? For the interrupt tests of `bench` and `sweep`.

A result file is complete when its format's own end marker is there and it parses: JSON
loads, CSV rows all have the header's width, PNG ends with its IEND chunk, an MP4's boxes
tile the file exactly and include `moov`, an .npz is a readable zip of arrays, text ends
with a newline. harness.io.atomic_write writes to a hidden temporary `.<name>.<random>`
beside the target and renames it: after SIGKILL such a temporary may remain (nothing can
delete it), so temporaries are listed apart and are never taken for results.
"""

from __future__ import annotations

import csv
import json
import struct
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import numpy as np


def is_temporary(path: Path) -> bool:
    """A temporary of harness.io.atomic_write (hidden, '.<target name>.<random>')."""
    return path.name.startswith(".")


def _json(path: Path) -> None:
    json.loads(path.read_text())


def _text(path: Path) -> None:
    text = path.read_text()
    assert text.endswith("\n"), "does not end with a newline"


def _csv(path: Path) -> None:
    _text(path)
    rows = list(csv.reader(path.read_text().splitlines()))
    assert rows, "empty"
    widths = {len(r) for r in rows}
    assert len(widths) == 1, f"rows of widths {sorted(widths)}"


def _png(path: Path) -> None:
    data = path.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n"), "no PNG signature"
    assert data[-12:] == struct.pack(">I", 0) + b"IEND" + struct.pack(">I", 0xAE426082), "no IEND"


def _mp4(path: Path) -> None:
    data, k, boxes = path.read_bytes(), 0, []
    while k < len(data):
        assert k + 8 <= len(data), "truncated box header"
        size, kind = struct.unpack(">I4s", data[k:k + 8])
        if size == 1:
            size = struct.unpack(">Q", data[k + 8:k + 16])[0]
        assert size >= 8 and k + size <= len(data), f"box {kind!r} runs past the end"
        boxes.append(kind)
        k += size
    assert b"moov" in boxes and b"mdat" in boxes, f"boxes {boxes}"


def _xml(path: Path) -> None:
    ElementTree.parse(path)


def _npz(path: Path) -> None:
    with zipfile.ZipFile(path) as z:
        assert z.testzip() is None
    with np.load(path, allow_pickle=False) as npz:
        for key in npz.files:
            npz[key]


CHECKS = {".json": _json, ".md": _text, ".txt": _text, ".csv": _csv, ".png": _png,
          ".mp4": _mp4, ".npz": _npz, ".xml": _xml}


def incomplete_files(folder: Path) -> tuple[list[str], list[str]]:
    """(result files under folder that are incomplete, with the reason; temporaries left)."""
    bad, temporaries = [], []
    for path in sorted(Path(folder).rglob("*")):
        if not path.is_file():
            continue
        if is_temporary(path):
            temporaries.append(str(path))
            continue
        check = CHECKS.get(path.suffix.lower())
        if check is None:
            bad.append(f"{path}: unknown result type")
            continue
        try:
            check(path)
        except (AssertionError, ValueError, OSError, zipfile.BadZipFile, struct.error,
                ElementTree.ParseError) as exc:
            bad.append(f"{path}: {exc or type(exc).__name__}")
    return bad, temporaries
