#!/usr/bin/env python
# ruff: noqa
"""Serve a state machine as an action and call it from another machine (ROS 1 era)."""

import rospy
import smach
import smach_ros
from actionlib_tutorials.msg import FibonacciAction, FibonacciGoal, FibonacciResult


@smach.cb_interface(input_keys=["goal"], output_keys=["result"], outcomes=["computed"])
def compute(ud):
    sequence = [0, 1]
    while len(sequence) < ud.goal.order:
        sequence.append(sequence[-1] + sequence[-2])
    ud.result = FibonacciResult(sequence=sequence)
    return "computed"


def main():
    rospy.init_node("port_wrapper")
    server_sm = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
    with server_sm:
        smach.StateMachine.add(
            "COMPUTE", smach.CBState(compute), transitions={"computed": "succeeded"}
        )
    asw = smach_ros.ActionServerWrapper(
        "port_wrapped",
        FibonacciAction,
        wrapped_container=server_sm,
        succeeded_outcomes=["succeeded"],
        aborted_outcomes=["aborted"],
        preempted_outcomes=["preempted"],
        goal_key="goal",
        result_key="result",
    )
    asw.run_server()

    client_sm = smach.StateMachine(outcomes=["done", "failed"])
    with client_sm:
        smach.StateMachine.add(
            "ASK",
            smach_ros.SimpleActionState(
                "port_wrapped", FibonacciAction, goal=FibonacciGoal(order=6), result_key="answer"
            ),
            transitions={"succeeded": "done", "aborted": "failed", "preempted": "failed"},
        )
    outcome = client_sm.execute()
    print("outcome: %s answer: %s" % (outcome, list(client_sm.userdata.answer.sequence)))


if __name__ == "__main__":
    main()
