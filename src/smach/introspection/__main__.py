"""``python -m smach.introspection view|export RUN.jsonl`` (see :mod:`.cli`)."""

import sys

from smach.introspection.cli import main

sys.exit(main())
