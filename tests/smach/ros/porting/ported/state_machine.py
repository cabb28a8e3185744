#!/usr/bin/env python
# ruff: noqa
"""A patrol loop with userdata remapping and an introspection server (ROS 1 era)."""

import time
import smach
import smach_ros


class Patrol(smach.State):
    def __init__(self):
        smach.State.__init__(
            self, outcomes=["tired", "continue"], input_keys=["laps_in"], output_keys=["laps_out"]
        )

    def execute(self, userdata):
        smach.loginfo("Patrolling lap %d" % userdata.laps_in)
        userdata.laps_out = userdata.laps_in + 1
        if userdata.laps_in < 3:
            return "continue"
        return "tired"


class Recharge(smach.State):
    def __init__(self):
        smach.State.__init__(self, outcomes=["charged"], input_keys=["laps"])

    def execute(self, userdata):
        smach.loginfo("Recharging after %d laps" % userdata.laps)
        time.sleep(0.01)
        return "charged"


def main():
    sm = smach.StateMachine(outcomes=["finished"])
    sm.userdata.laps = 0
    with sm:
        smach.StateMachine.add(
            "PATROL",
            Patrol(),
            transitions={"continue": "PATROL", "tired": "RECHARGE"},
            remapping={"laps_in": "laps", "laps_out": "laps"},
        )
        smach.StateMachine.add("RECHARGE", Recharge(), transitions={"charged": "finished"})
    sis = smach_ros.IntrospectionServer("port_patrol_server", sm, "/SM_ROOT")
    sis.start()
    outcome = sm.execute()
    sis.stop()
    print("outcome: %s laps: %d" % (outcome, sm.userdata.laps))


if __name__ == "__main__":
    main()
