"""User-facing errors: the CLI prints their message on one line and exits 2."""


class UserError(ValueError):
    """Bad input a user can fix: missing file, unknown robot, malformed data."""
