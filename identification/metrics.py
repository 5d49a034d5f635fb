"""Error measures shared by identification, the close-the-loop analysis and the report."""

from __future__ import annotations

import numpy as np


def rel_error(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Per-column (per-joint) relative RMS error ||estimate - truth|| / ||truth||.

    Arrays of shape (n, dof) give a (dof,) array; a column whose truth is zero
    divides by 1e-300 instead (an infinite or zero error, never NaN from 0/0 alone).
    """
    return np.linalg.norm(estimate - truth, axis=0) / np.maximum(
        np.linalg.norm(truth, axis=0), 1e-300)


ERROR_NAME = "relative RMS error"
ERROR_FORMULA = "||estimate - reference|| / ||reference|| per joint over the scored samples"
HELD_OUT = "the held-out samples (the last --holdout of the runs, or the --validate runs)"
REFERENCES = {"clean": "the noise-free torque (tau_clean)",
              "measured": "the measured torque (tau)",
              "states": "MuJoCo's simulated states"}


def error_reference(has_clean: bool) -> str:
    """The one rule for a torque error's reference: the noise-free torque where the data carry
    it (simulated data), else the measured one."""
    return "clean" if has_clean else "measured"


def error_measure(reference: str, samples: str) -> dict:
    """How an error figure was computed, as every command writes it beside its figures:
    reference one of REFERENCES' keys; samples: which were scored (e.g. "the held-out part")."""
    return {"name": ERROR_NAME, "formula": ERROR_FORMULA, "unit": "fraction",
            "reference": REFERENCES[reference], "samples": samples}


def error_words(reference: str, samples: str) -> str:
    """The same, as every command prints it before its figures."""
    return f"{ERROR_NAME} against {REFERENCES[reference]}, {samples} (a fraction, per joint)"


def error_figures(values) -> str:
    """Per-joint error figures as every command prints them."""
    return "[" + ", ".join(f"{float(v):.4g}" for v in values) + "]"
