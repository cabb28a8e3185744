#!/usr/bin/env python
# ruff: noqa
"""Switch a flag through a service; request from a userdata slot (ROS 1 era)."""

import rclpy
import smach
import smach_ros
from std_srvs.srv import SetBool


@smach.cb_interface(output_keys=["reply"], outcomes=["accepted", "refused"])
def on_response(ud, response):
    ud.reply = response.message
    return "accepted" if response.success else "refused"


def main():
    rclpy.init()
    sm = smach.StateMachine(outcomes=["on", "off", "failed"])
    sm.userdata.data = True
    with sm:
        smach.StateMachine.add(
            "SWITCH_ON",
            smach_ros.ServiceState(
                "port_setbool", SetBool, request_slots=["data"], response_cb=on_response
            ),
            transitions={
                "accepted": "SWITCH_OFF",
                "refused": "failed",
                "succeeded": "failed",
                "aborted": "failed",
                "preempted": "failed",
            },
        )
        smach.StateMachine.add(
            "SWITCH_OFF",
            smach_ros.ServiceState("port_setbool", SetBool, request=SetBool.Request(data=False)),
            transitions={"succeeded": "off", "aborted": "failed", "preempted": "failed"},
        )
    outcome = sm.execute()
    print("outcome: %s reply: %s" % (outcome, sm.userdata.reply))


if __name__ == "__main__":
    main()
