#!/usr/bin/env python
# ruff: noqa
"""Search and wave at the same time; an outcome map decides (ROS 1 era)."""

import time
import smach


class Search(smach.State):
    def __init__(self):
        smach.State.__init__(self, outcomes=["found", "lost"], output_keys=["where"])

    def execute(self, ud):
        time.sleep(0.05)
        ud.where = "kitchen"
        return "found"


class Wave(smach.State):
    def __init__(self):
        smach.State.__init__(self, outcomes=["done"])

    def execute(self, ud):
        for _ in range(3):
            if self.preempt_requested():
                self.service_preempt()
                return "done"
            time.sleep(0.01)
        return "done"


def main():
    sm = smach.StateMachine(outcomes=["greeted", "alone"], output_keys=["room"])
    with sm:
        cc = smach.Concurrence(
            outcomes=["succeeded", "failed"],
            default_outcome="failed",
            output_keys=["where"],
            outcome_map={"succeeded": {"SEARCH": "found", "WAVE": "done"}},
        )
        with cc:
            smach.Concurrence.add("SEARCH", Search())
            smach.Concurrence.add("WAVE", Wave())
        smach.StateMachine.add(
            "MEET",
            cc,
            transitions={"succeeded": "greeted", "failed": "alone"},
            remapping={"where": "room"},
        )
    outcome = sm.execute()
    smach.loginfo("met in %s" % sm.userdata.room)
    print("outcome: %s room: %s" % (outcome, sm.userdata.room))


if __name__ == "__main__":
    main()
