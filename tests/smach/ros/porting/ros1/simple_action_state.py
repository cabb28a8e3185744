#!/usr/bin/env python
# ruff: noqa
"""Ask an action server for Fibonacci numbers, goal from userdata (ROS 1 era)."""

import rospy
import smach
import smach_ros
from actionlib_msgs.msg import GoalStatus
from actionlib_tutorials.msg import FibonacciAction, FibonacciGoal


@smach.cb_interface(input_keys=["order"])
def make_goal(ud, goal):
    return FibonacciGoal(order=ud.order)


@smach.cb_interface(output_keys=["last"], outcomes=["long_enough"])
def check_result(ud, status, result):
    if status == GoalStatus.SUCCEEDED and len(result.sequence) > 3:
        ud.last = result.sequence[-1]
        return "long_enough"
    return None


def main():
    rospy.init_node("port_action_client")
    sm = smach.StateMachine(outcomes=["done", "failed"])
    sm.userdata.order = 5
    with sm:
        smach.StateMachine.add(
            "FIXED_GOAL",
            smach_ros.SimpleActionState(
                "port_fibonacci",
                FibonacciAction,
                goal=FibonacciGoal(order=2),
                result_slots=["sequence"],
                server_wait_timeout=rospy.Duration(20.0),
            ),
            transitions={
                "succeeded": "GOAL_FROM_USERDATA",
                "aborted": "failed",
                "preempted": "failed",
            },
            remapping={"sequence": "first"},
        )
        smach.StateMachine.add(
            "GOAL_FROM_USERDATA",
            smach_ros.SimpleActionState(
                "port_fibonacci", FibonacciAction, goal_cb=make_goal, result_cb=check_result
            ),
            transitions={
                "long_enough": "done",
                "succeeded": "failed",
                "aborted": "failed",
                "preempted": "failed",
            },
        )
    outcome = sm.execute()
    print("outcome: %s first: %s last: %s" % (outcome, list(sm.userdata.first), sm.userdata.last))


if __name__ == "__main__":
    main()
