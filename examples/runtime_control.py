"""Runtime control of a running machine: a breakpoint, resume, and a forced outcome.

A person finishes the grasp by hand and tells the machine it succeeded. The same
code is in docs/control.md.
"""

import threading

import smach
from smach.control import Controller
from smach.testing import BlockingState, ScriptedState

sm = smach.StateMachine(outcomes=["done", "failed", "preempted"])
sm.add("APPROACH", ScriptedState(["ok"], outcomes=["ok"]), transitions={"ok": "GRASP"})
grasp = BlockingState(outcomes=("grasped", "missed", "preempted"))
sm.add("GRASP", grasp, transitions={"grasped": "done", "missed": "failed"})

ctl = Controller(sm)  # one controller per tree, attach before or during a run
ctl.add_breakpoint("*/GRASP")  # a path or an fnmatch pattern
result = []
runner = threading.Thread(target=lambda: result.append(sm.execute()))
runner.start()

assert ctl.wait_for("at_breakpoint", timeout=5)
print(ctl.status().describe())  # at breakpoint /ROOT/GRASP
ctl.resume()  # GRASP starts
grasp.started.wait(5)
ctl.force_outcome("grasped")  # a person did it by hand
runner.join(5)
assert result == ["done"]
print([(r.action, r.source) for r in ctl.history])
# [('add_breakpoint', 'api'), ('breakpoint_hit', 'machine'), ('resume', 'api'),
#  ('force_outcome', 'api'), ('outcome_forced', 'machine')]
ctl.close()
