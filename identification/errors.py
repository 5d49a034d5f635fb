"""Errors and warnings of the identification package."""

from __future__ import annotations


class IdentificationError(ValueError):
    """Bad identification input a user can fix (NaN, shapes, too few samples, ...).

    The CLI prints its message on one line and exits 2.
    """


class LibraryRankWarning(UserWarning):
    """The feature library is rank deficient on the data: some features are collinear."""
