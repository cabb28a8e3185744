#!/usr/bin/env python
# ruff: noqa
"""ROS 2 smach_ros style: the node first, spun by the script, the server a node too."""

import threading

import rclpy
import smach
import smach_ros
from rclpy.executors import MultiThreadedExecutor
from std_msgs.msg import String
from std_srvs.srv import SetBool
from test_msgs.action import Fibonacci


def main():
    rclpy.init()
    node = rclpy.create_node("port_ros2_client")
    sm = smach.StateMachine(outcomes=["done", "failed"])
    with sm:
        smach.StateMachine.add(
            "LISTEN",
            smach_ros.MonitorState(
                node, "/port_chatter", String, lambda ud, msg: True, max_checks=2
            ),
            transitions={"valid": "SWITCH", "invalid": "failed", "preempted": "failed"},
        )
        smach.StateMachine.add(
            "SWITCH",
            smach_ros.ServiceState(
                node, "port_setbool", SetBool, request=SetBool.Request(data=True)
            ),
            transitions={"succeeded": "COUNT", "aborted": "failed", "preempted": "failed"},
        )
        smach.StateMachine.add(
            "COUNT",
            smach_ros.SimpleActionState(
                node, "port_fibonacci", Fibonacci, goal=Fibonacci.Goal(order=3)
            ),
            transitions={"succeeded": "POLL", "aborted": "failed", "preempted": "failed"},
        )
        smach.StateMachine.add(
            "POLL",
            smach_ros.ConditionState(node, lambda ud: True, poll_rate=50.0),
            transitions={"true": "done", "false": "failed", "preempted": "failed"},
        )
    sis = smach_ros.IntrospectionServer("port_ros2_intro", sm, "/SM_ROOT")
    executor = MultiThreadedExecutor()
    executor.add_node(node)
    executor.add_node(sis)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    sis.start()
    outcome = sm.execute()
    sis.stop()
    print("outcome: %s server node: %s" % (outcome, sis.get_name()))
    executor.shutdown()
    sis.destroy_node()
    node.destroy_node()
    rclpy.shutdown()
    spinner.join(5)


if __name__ == "__main__":
    main()
