"""Writing figures: the one place that picks matplotlib's file backend (Agg, no display).

Every figure module imports `plt` and `save_figure` from here, so the backend is set once,
before pyplot is first imported, whichever module loads first.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from harness.io import atomic_write  # noqa: E402

__all__ = ["plt", "save_figure"]


def save_figure(fig, path: Path, dpi: int = 120, tight: str = "layout") -> Path:
    """Write a finished figure as PNG and release it.

    tight: "layout" (fig.tight_layout before saving), "bbox" (crop to the drawn content,
    bbox_inches="tight") or "none"."""
    path = Path(path)
    if tight == "layout":
        fig.tight_layout()
    try:  # complete or absent, like every result file
        atomic_write(path, lambda tmp: fig.savefig(tmp, format="png", dpi=dpi,
                                                  bbox_inches="tight" if tight == "bbox" else None),
                     suffix=".png")
    finally:
        plt.close(fig)
    return path
