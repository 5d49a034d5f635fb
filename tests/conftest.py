"""Hypothesis profiles: `TORQUEBENCH_HYPOTHESIS=full` (make test, CI) generates over 1000
cases across the loader properties (6 x 250) (tests/test_loaders_property.py); the default stays fast."""

import os

from hypothesis import HealthCheck, settings

_COMMON = dict(deadline=None, derandomize=False, print_blob=True,
               suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                      HealthCheck.data_too_large])
settings.register_profile("default", max_examples=30, **_COMMON)
settings.register_profile("full", max_examples=250, **_COMMON)
settings.load_profile(os.environ.get("TORQUEBENCH_HYPOTHESIS", "default"))
