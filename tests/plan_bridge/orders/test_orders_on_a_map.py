"""Orders in a pyrobosim world: the fleet serves them, and a robot low on battery charges."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from plan_bridge.missions.mission import load_target
from plan_bridge.missions.runner import MissionOptions, prepare_mission
from plan_bridge.missions.world_target import LOW_BATTERY, WorldTarget
from plan_bridge.orders.order_executive import OrderExecutive

TWO_ROBOTS = Path(__file__).parents[3] / "domains" / "robosim_two_robots"

pytestmark = pytest.mark.timeout(300)


def low_battery_copy(folder: Path, robot: str, level: float) -> Path:
    """The two-robot world with ``robot``'s battery at ``level`` percent."""
    shutil.copytree(TWO_ROBOTS, folder)
    world = folder / "world.yaml"
    lines = world.read_text(encoding="utf-8").splitlines()
    current = None
    for i, line in enumerate(lines):
        if line.strip().startswith("- name:"):
            current = line.split(":", 1)[1].strip()
        if current == robot and "initial_battery_level" in line:
            lines[i] = line.split(":")[0] + f": {level}"
    world.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return folder


def test_robots_below_the_low_mark_get_a_charge_goal() -> None:
    target = load_target(TWO_ROBOTS)
    assert isinstance(target, WorldTarget)
    values = {("battery-level", "ada"): LOW_BATTERY - 1, ("battery-level", "bob"): 90.0}
    assert target.upkeep_goals(frozenset(), values) == [("charged", "ada")]


def test_a_robot_low_on_battery_charges_while_the_fleet_serves_the_orders(tmp_path: Path) -> None:
    folder = low_battery_copy(tmp_path / "world", "bob", 30.0)
    orders = tmp_path / "orders.yaml"
    orders.write_text("- {id: wrench, at: 0, goal: wrench_to_lab}\n", encoding="utf-8")
    mission = prepare_mission(
        load_target(folder), MissionOptions(seed=2, fail_rate=0.0, orders=str(orders))
    )
    executive = mission.executive
    assert isinstance(executive, OrderExecutive)
    mission.run()
    assert executive.orders.get("wrench").status == "done"
    charges = [step for step in executive.report.executed if step.startswith("(charge bob")]
    assert charges, executive.report.executed
    battery = executive.belief.values[("battery-level", "bob")]
    assert battery >= LOW_BATTERY
