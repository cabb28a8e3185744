"""Test-wide settings: keep ROS 2 traffic on this machine, one DDS domain per run, and
Ctrl-C reaches the command-line programs the tests start."""

from __future__ import annotations

import os
import random
import signal

# DDS would otherwise multicast off the machine; a random domain per run keeps
# concurrent test runs apart.
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", str(random.randint(101, 200)))

# A suite started in the background by a non-interactive shell (`.ci/run &`) inherits
# SIGINT ignored, and every program it starts would too: the tests that press Ctrl-C
# on `plan-bridge run --viewer` or the viewer CLI would wait for an exit that never
# comes. A handled signal is reset to its default in the programs started from here.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)
