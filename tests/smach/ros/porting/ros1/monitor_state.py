#!/usr/bin/env python
# ruff: noqa
"""Watch a topic until three messages passed a check (ROS 1 era)."""

import rospy
import smach
import smach_ros
from std_msgs.msg import String


def looks_fine(ud, msg):
    ud.seen = ud.seen + 1
    return msg.data.startswith("message")


def main():
    rospy.init_node("port_monitor")
    sm = smach.StateMachine(outcomes=["calm", "alarm"])
    sm.userdata.seen = 0
    with sm:
        smach.StateMachine.add(
            "WATCH",
            smach_ros.MonitorState(
                "/port_chatter",
                String,
                looks_fine,
                max_checks=3,
                input_keys=["seen"],
                output_keys=["seen"],
            ),
            transitions={"valid": "calm", "invalid": "alarm", "preempted": "alarm"},
        )
    outcome = sm.execute()
    print("outcome: %s seen: %d" % (outcome, sm.userdata.seen))


if __name__ == "__main__":
    main()
