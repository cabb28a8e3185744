"""The courier robot's ROS 2 servers, in a process of their own.

    python domains/ros_courier/robot.py [--fail-rate P] [--seed N] [--drive-time S] [--lease S]

Serves what ``skills.toml`` binds the domain's actions to:

* ``/courier/set_pose`` (``nav_msgs/srv/SetMap``): takes the initial pose;
* ``/courier/drive`` (``test_msgs/action/Fibonacci``): drives to the waypoint
  ``order`` in ``--drive-time`` seconds, with feedback (the share of the way
  driven, in percent) every tenth of it; a cancel stops it where it is;
* ``/courier/gripper`` (``std_srvs/srv/SetBool``): closes (``data = true``) or
  opens the gripper; opening it delivers what it held where the robot is;
* ``/courier/receipts`` (``std_msgs/msg/String``): ``delivered at PLACE`` after
  each delivery, published ten times a second.

With ``--fail-rate P`` each goal or call fails with probability P (seeded): the
drive is blocked (ABORTED) or ends off its route (SUCCEEDED with ``sequence ==
[0]``), the gripper slips (``success = false``), localisation fails
(``success = false``). It prints ``ready`` once serving, and one line per goal,
call, fault and cancel. ``--lease S`` (default 2) is the DDS lease: a killed
server leaves the ROS graph after about S seconds, so the executive notices.
"""

from __future__ import annotations

import argparse
import random
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent


def _say(text: str) -> None:
    print(text, flush=True)


class CourierRobot:
    """The servers and the little the robot knows: where it is, what it holds."""

    def __init__(self, node: Any, *, fail_rate: float, seed: int, drive_time: float) -> None:
        import yaml
        from nav_msgs.srv import SetMap
        from rclpy.action import ActionServer, CancelResponse, GoalResponse
        from rclpy.callback_groups import ReentrantCallbackGroup
        from std_msgs.msg import String
        from std_srvs.srv import SetBool
        from test_msgs.action import Fibonacci

        waypoints = yaml.safe_load((HERE / "waypoints.yaml").read_text(encoding="utf-8"))
        self.places = {int(number): name for name, number in waypoints.items()}
        self.rng = random.Random(seed)
        self.fail_rate = fail_rate
        self.drive_time = drive_time
        self.lock = threading.Lock()
        self.where = 0  # unknown until localised
        self.holding = False
        self.receipt = ""
        self.fibonacci = Fibonacci
        self.string = String
        group = ReentrantCallbackGroup()
        self.drive_server = ActionServer(
            node,
            Fibonacci,
            "/courier/drive",
            execute_callback=self.drive,
            goal_callback=lambda goal: GoalResponse.ACCEPT,
            cancel_callback=lambda handle: CancelResponse.ACCEPT,
            callback_group=group,
        )
        node.create_service(SetMap, "/courier/set_pose", self.set_pose, callback_group=group)
        node.create_service(SetBool, "/courier/gripper", self.gripper, callback_group=group)
        self.receipts = node.create_publisher(String, "/courier/receipts", 10)
        node.create_timer(0.1, self.publish_receipt, callback_group=group)

    def fault(self) -> bool:
        return self.fail_rate > 0 and self.rng.random() < self.fail_rate

    def set_pose(self, request: Any, response: Any) -> Any:
        pose = request.initial_pose.pose.pose.position
        with self.lock:
            failed = self.fault()
            if not failed:
                near = {name: number for number, name in self.places.items()}
                self.where = near.get(self._place_at(pose.x, pose.y), 0)
        _say(
            f"set_pose ({pose.x:g}, {pose.y:g}) in {request.initial_pose.header.frame_id}: "
            + ("fault: not localised" if failed else f"at {self.places.get(self.where, '?')}")
        )
        response.success = not failed
        return response

    @staticmethod
    def _place_at(x: float, y: float) -> str:
        import yaml

        poses = yaml.safe_load((HERE / "poses.yaml").read_text(encoding="utf-8"))
        for name, pose in poses.items():
            position = pose.get("position", {})
            if abs(position.get("x", 0.0) - x) < 0.5 and abs(position.get("y", 0.0) - y) < 0.5:
                return str(name)
        return ""

    def drive(self, handle: Any) -> Any:
        target = int(handle.request.order)
        result = self.fibonacci.Result()
        name = self.places.get(target)
        _say(f"goal drive to {name or target}")
        with self.lock:
            kind = "" if not self.fault() else self.rng.choice(["blocked", "off-route"])
        if name is None:
            handle.abort()
            _say(f"aborted: no waypoint {target}")
            return result
        for tenth in range(1, 11):
            if kind == "blocked" and tenth == 5:
                handle.abort()
                _say(f"fault: blocked on the way to {name}")
                return result
            if not self._drive_on(handle, time.monotonic() + self.drive_time / 10):
                handle.canceled()
                _say(f"canceled drive to {name}")
                return result
            handle.publish_feedback(self.fibonacci.Feedback(sequence=[tenth * 10]))
        if kind == "off-route":
            _say(f"fault: off route, never reached {name}")
            result.sequence = [0]
        else:
            with self.lock:
                self.where = target
            result.sequence = [target]
            _say(f"succeeded drive to {name}")
        handle.succeed()
        return result

    @staticmethod
    def _drive_on(handle: Any, until: float) -> bool:
        """Drive until ``until``; False as soon as the goal is to be cancelled."""
        while time.monotonic() < until:
            if handle.is_cancel_requested:
                return False
            time.sleep(0.01)
        return not handle.is_cancel_requested

    def gripper(self, request: Any, response: Any) -> Any:
        with self.lock:
            if request.data:
                failed = self.fault()
                self.holding = not failed
                response.success = not failed
                response.message = "slipped" if failed else "holding"
                _say("gripper close: " + ("fault: slipped" if failed else "holding"))
            else:
                if self.holding:
                    self.receipt = f"delivered at {self.places.get(self.where, 'nowhere')}"
                self.holding = False
                response.success = True
                response.message = "open"
                _say(f"gripper open at {self.places.get(self.where, '?')}")
        return response

    def publish_receipt(self) -> None:
        with self.lock:
            receipt = self.receipt
        if receipt:
            self.receipts.publish(self.string(data=receipt))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--fail-rate", type=float, default=0.0, help="fault probability per goal or call"
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--drive-time", type=float, default=0.3, help="seconds per drive")
    parser.add_argument(
        "--lease", type=float, default=2.0, help="DDS lease in seconds (0: default)"
    )
    args = parser.parse_args(argv)
    if not 0.0 <= args.fail_rate <= 1.0:
        parser.error(f"--fail-rate must be between 0 and 1, got {args.fail_rate}")
    from plan_bridge.ros.lease import select_short_lease

    profile = select_short_lease(args.lease)
    from smach.ros._api import MultiThreadedExecutor, rclpy

    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    rclpy.init()
    node = rclpy.create_node("courier_robot")
    CourierRobot(node, fail_rate=args.fail_rate, seed=args.seed, drive_time=args.drive_time)
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    _say("ready")
    try:
        while not stop.wait(0.1):
            pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
        if profile is not None:
            profile.unlink(missing_ok=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
