#!/usr/bin/env python
# ruff: noqa
"""Poll conditions: one that becomes true, one that times out (ROS 1 era)."""

import itertools

import rclpy
import smach
import smach_ros

polls = itertools.count(1)


@smach.cb_interface(input_keys=["needed"])
def charged(ud):
    return next(polls) >= ud.needed


def main():
    rclpy.init()
    sm = smach.StateMachine(outcomes=["ready", "stuck"])
    sm.userdata.needed = 3
    with sm:
        smach.StateMachine.add(
            "WAIT_CHARGED",
            smach_ros.ConditionState(
                charged, poll_rate=rclpy.duration.Duration(seconds=0.01), max_checks=5
            ),
            transitions={"true": "WAIT_DOOR", "false": "stuck", "preempted": "stuck"},
        )
        smach.StateMachine.add(
            "WAIT_DOOR",
            smach_ros.ConditionState(
                lambda ud: False,
                poll_rate=0.01,
                timeout=rclpy.duration.Duration(seconds=0.1),
                max_checks=-1,
            ),
            transitions={"true": "stuck", "false": "ready", "preempted": "stuck"},
        )
    outcome = sm.execute()
    print("outcome: %s polls: %d" % (outcome, next(polls) - 1))


if __name__ == "__main__":
    main()
