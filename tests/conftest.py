"""Test configuration: under CI, hypothesis runs derandomized so a run is reproducible."""

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True, deadline=None)

# The one-time "compiling the simulation loop" notice depends on the state of the numba cache, not
# on what a test checks; tests that count stderr lines would see it only on a cold cache (CI).
# It is switched off here and tested on its own (test_cli_habits, which switches it back on).
os.environ.setdefault("ACDRIVE_COMPILE_NOTICE", "0")
if os.environ.get("CI"):
    settings.load_profile("ci")
