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
# Every test runs numba's specialised loop unless it asks for the native one
# (tests/test_native_tier.py compares the two bit for bit), so that what a test exercises does
# not depend on whether the machine has a C compiler.
os.environ.setdefault("ACDRIVE_LOOP_TIER", "specialised")
if not os.environ.get("ACDRIVE_FUZZ_RANDOM"):
    settings.load_profile("ci")

# A suite started in the background by a non-interactive shell (`nohup pytest &`) inherits SIGINT
# ignored, and so would every command a test starts: Python then installs no KeyboardInterrupt
# handler and the tests that interrupt a run with SIGINT would see it run to its end. Restoring
# Python's handler here makes the children start with SIGINT at its default again.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)
