"""Test-wide settings: keep ROS 2 traffic on this machine, one DDS domain per run."""

from __future__ import annotations

import os
import random

# DDS would otherwise multicast off the machine; a random domain per run keeps
# concurrent test runs apart.
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", str(random.randint(101, 200)))
