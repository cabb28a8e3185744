"""``python -m plan_bridge``: the same as the ``plan-bridge`` command."""

import sys

from plan_bridge.cli import main

sys.exit(main())
