"""Test configuration: hypothesis runs derandomized (a fixed sequence of examples) so that a
test run is reproducible and CI judges the change, not the draw; ``ACDRIVE_FUZZ_RANDOM=1`` draws
fresh examples for a fuzzing session on a developer's machine."""

import os
import signal

from hypothesis import settings

settings.register_profile("ci", derandomize=True, deadline=None)

# The one-time "compiling the simulation loop" notice depends on the state of the numba cache, not
# on what a test checks; tests that count stderr lines would see it only on a cold cache (CI).
# It is switched off here and tested on its own (test_cli_habits, which switches it back on).
os.environ.setdefault("ACDRIVE_COMPILE_NOTICE", "0")
# Nor does the suite start background compiles (sim._tier): a test's processes end with the test;
# the tests of the background compile switch it on for their own processes.
os.environ.setdefault("ACDRIVE_BACKGROUND_COMPILE", "0")
# Every test runs the specialised loop unless it asks for another tier (tests/test_tiers.py
# compares the generic loop with it): which tier an "auto" run picks depends on what earlier
# tests left compiled in the cache, and under fast-math the tiers agree to rounding, not bits,
# so a comparison of two runs must not depend on the order the tests ran in.
os.environ.setdefault("ACDRIVE_LOOP_TIER", "specialised")
if not os.environ.get("ACDRIVE_FUZZ_RANDOM"):
    settings.load_profile("ci")

# A suite started in the background by a non-interactive shell (`nohup pytest &`) inherits SIGINT
# ignored, and so would every command a test starts: Python then installs no KeyboardInterrupt
# handler and the tests that interrupt a run with SIGINT would see it run to its end. Restoring
# Python's handler here makes the children start with SIGINT at its default again.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)
