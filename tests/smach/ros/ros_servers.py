"""ROS 2 servers for the smach.ros tests, run in separate processes.

    python ros_servers.py fibonacci NAME [--mode MODE] [--step S]
    python ros_servers.py setbool NAME [--mode MODE]
    python ros_servers.py publish TOPIC --rate HZ

Fibonacci modes: ``normal`` (one feedback per step of ``--step`` seconds),
``reject``, ``abort`` (aborts after one step), ``slow-cancel`` (takes 0.7 s to
finish cancelling), ``ignore-cancel`` (refuses cancel requests). SetBool modes:
``normal`` (answers ``success = data``), ``crash`` (the process dies in the
callback), ``slow`` (answers after 30 s). Prints ``ready`` once serving and a line
per event (``goal``, ``cancel``, ``canceled``) so tests can follow the server.
The caller sets ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST and ROS_DOMAIN_ID.
"""

from __future__ import annotations

import argparse
import itertools
import os
import sys
import threading
import time
import warnings

with warnings.catch_warnings():
    warnings.filterwarnings("ignore", category=DeprecationWarning)
    import rosidl_generator_py  # noqa: F401  (lark's sre_parse warning, once)

import contextlib

import rclpy
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor


def say(text: str) -> None:
    print(text, flush=True)


def fibonacci(node, name: str, mode: str, step: float, stop=None) -> object:  # type: ignore[no-untyped-def]
    """The Fibonacci server; a goal running when ``stop`` (an Event) is set aborts, so
    that a test's clean-up never destroys the node under a running goal."""
    from test_msgs.action import Fibonacci

    def on_goal(goal):  # type: ignore[no-untyped-def]
        say("goal")
        return GoalResponse.REJECT if mode == "reject" else GoalResponse.ACCEPT

    def on_cancel(handle):  # type: ignore[no-untyped-def]
        say("cancel")
        return CancelResponse.REJECT if mode == "ignore-cancel" else CancelResponse.ACCEPT

    def execute(handle):  # type: ignore[no-untyped-def]
        order = handle.request.order
        sequence = [0, 1]
        for i in range(1, max(order, 1)):
            if stop is not None and stop.is_set():
                handle.abort()
                return Fibonacci.Result(sequence=sequence)
            if handle.is_cancel_requested:
                if mode == "slow-cancel":
                    time.sleep(0.7)
                handle.canceled()
                say("canceled")
                return Fibonacci.Result(sequence=sequence)
            if mode == "abort" and i == 2:
                handle.abort()
                say("aborted")
                return Fibonacci.Result(sequence=sequence)
            sequence.append((sequence[i] + sequence[i - 1]) % 1_000_000)
            handle.publish_feedback(Fibonacci.Feedback(sequence=sequence))
            time.sleep(step)
        handle.succeed()
        say("succeeded")
        return Fibonacci.Result(sequence=sequence)

    return ActionServer(
        node,
        Fibonacci,
        name,
        execute,
        goal_callback=on_goal,
        cancel_callback=on_cancel,
        callback_group=ReentrantCallbackGroup(),
    )


def setbool(node, name: str, mode: str) -> object:  # type: ignore[no-untyped-def]
    from std_srvs.srv import SetBool

    calls = itertools.count(1)

    def handle(request, response):  # type: ignore[no-untyped-def]
        call = next(calls)
        say("request")
        if mode == "crash":
            os._exit(3)  # a crash: no clean-up, the process leaves the graph by its lease
        if mode == "slow" or (mode == "slow_first" and call == 1):
            time.sleep(30)
        response.success = request.data
        response.message = f"got {request.data}"
        return response

    return node.create_service(SetBool, name, handle, callback_group=ReentrantCallbackGroup())


def publish(node, topic: str, rate: float) -> threading.Thread:  # type: ignore[no-untyped-def]
    from std_msgs.msg import String

    pub = node.create_publisher(String, topic, 10)

    def loop() -> None:
        n = 0
        while rclpy.ok():
            n += 1
            pub.publish(String(data=f"message {n}"))
            time.sleep(1.0 / rate)

    thread = threading.Thread(target=loop, daemon=True)
    thread.start()
    return thread


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("kind", choices=["fibonacci", "setbool", "publish"])
    parser.add_argument("name")
    parser.add_argument("--mode", default="normal")
    parser.add_argument("--step", type=float, default=0.1)
    parser.add_argument("--rate", type=float, default=20.0)
    args = parser.parse_args()
    rclpy.init()
    node = rclpy.create_node("test_server")
    if args.kind == "fibonacci":
        keep = fibonacci(node, args.name, args.mode, args.step)
    elif args.kind == "setbool":
        keep = setbool(node, args.name, args.mode)
    else:
        keep = publish(node, args.name, args.rate)
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    say("ready")
    with contextlib.suppress(KeyboardInterrupt, ExternalShutdownException):
        executor.spin()
    del keep
    return 0


if __name__ == "__main__":
    sys.exit(main())
