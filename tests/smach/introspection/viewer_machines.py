"""Machines and helpers shared by the viewer tests."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import smach
from smach.testing import BlockingState

REPO = Path(__file__).resolve().parents[3]
ARTIFACTS = REPO / "artifacts" / "viewer"
ROOMS = REPO / "tests" / "plan_bridge" / "data" / "rooms"


class Count(smach.State):
    """Increments ``n`` and writes a small record of it."""

    def __init__(self) -> None:
        super().__init__(outcomes=["ok"], input_keys=["n"], output_keys=["n", "log"])

    def execute(self, ud: smach.UserData) -> str:
        ud.n = ud.n + 1
        ud.log = {"last": ud.n, "items": list(range(ud.n))}
        return "ok"


class Stubborn(smach.State):
    """Keeps running after a preempt request until released (to see the marker)."""

    def __init__(self) -> None:
        super().__init__(outcomes=["done", "preempted"])
        self.started = threading.Event()
        self.go = threading.Event()

    def execute(self, ud: smach.UserData) -> str:
        self.started.set()
        self.go.wait(30)
        if self.preempt_requested():
            self.service_preempt()
            return "preempted"
        return "done"


class Trivial(smach.State):
    def __init__(self, outcome: str = "done") -> None:
        super().__init__(outcomes=[outcome])
        self.outcome = outcome

    def execute(self, ud: smach.UserData) -> str:
        return self.outcome


def demo_machine() -> tuple[smach.StateMachine, dict[str, Any]]:
    """INIT -> FETCH (NAVIGATE -> PICK) -> PAR (ARM || BASE), PICK/ARM/BASE held."""
    sm = smach.StateMachine(outcomes=["done", "failed"])
    sm.userdata.n = 0
    hold: dict[str, Any] = {}
    with sm:
        smach.StateMachine.add("INIT", Count(), transitions={"ok": "FETCH"})
        fetch = smach.StateMachine(
            outcomes=["got", "lost"], input_keys=["n"], output_keys=["n", "log"]
        )
        with fetch:
            smach.StateMachine.add("NAVIGATE", Count(), transitions={"ok": "PICK"})
            hold["pick"] = BlockingState(outcomes=["picked", "missed", "preempted"], timeout=30)
            smach.StateMachine.add(
                "PICK",
                hold["pick"],
                transitions={"picked": "got", "missed": "lost", "preempted": "lost"},
            )
        smach.StateMachine.add("FETCH", fetch, transitions={"got": "PAR", "lost": "failed"})
        par = smach.Concurrence(
            outcomes=["ok", "bad"],
            default_outcome="bad",
            outcome_map={"ok": {"ARM": "done", "BASE": "done"}},
        )
        with par:
            hold["arm"] = BlockingState(outcomes=["done", "preempted"], timeout=30)
            hold["base"] = Stubborn()
            smach.Concurrence.add("ARM", hold["arm"])
            smach.Concurrence.add("BASE", hold["base"])
        smach.StateMachine.add("PAR", par, transitions={"ok": "done", "bad": "failed"})
    return sm, hold


def big_machine(chain: int = 30, branches: int = 8, nested: int = 4) -> smach.StateMachine:
    """A machine of 50+ states: a chain, nested machines and a wide Concurrence."""
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        for i in range(chain):
            smach.StateMachine.add(
                f"STEP_{i:02d}",
                Trivial(),
                transitions={"done": f"STEP_{i + 1:02d}" if i + 1 < chain else "MISSION"},
            )
        mission = smach.StateMachine(outcomes=["done"])
        with mission:
            for k in range(nested):
                inner = smach.StateMachine(outcomes=["done"])
                with inner:
                    smach.StateMachine.add("APPROACH", Trivial(), transitions={"done": "GRASP"})
                    smach.StateMachine.add("GRASP", Trivial(), transitions={"done": "LIFT"})
                    smach.StateMachine.add("LIFT", Trivial(), transitions={"done": "done"})
                nxt = f"TASK_{k + 1}" if k + 1 < nested else "SENSORS"
                smach.StateMachine.add(f"TASK_{k}", inner, transitions={"done": nxt})
            par = smach.Concurrence(outcomes=["done"], default_outcome="done")
            with par:
                for b in range(branches):
                    smach.Concurrence.add(f"SENSOR_{b}", Trivial())
            smach.StateMachine.add("SENSORS", par, transitions={"done": "done"})
        smach.StateMachine.add("MISSION", mission, transitions={"done": "done"})
    return sm


def chain_machine(n: int) -> smach.StateMachine:
    sm = smach.StateMachine(outcomes=["finished"])
    with sm:
        for i in range(n):
            smach.StateMachine.add(
                f"S{i}", Trivial(), transitions={"done": f"S{i + 1}" if i + 1 < n else "finished"}
            )
    return sm


def wait_until(
    predicate: Callable[[], bool], timeout: float = 10.0, what: str = "condition"
) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise TimeoutError(f"timed out waiting for {what}")
        time.sleep(0.02)


class PickFailsOnce:
    """A SimulatedWorld factory whose first ``pick`` fails (forces a replan)."""

    @staticmethod
    def world(task: Any) -> Any:
        from plan_bridge.execution.simulation import SimulatedWorld

        class World(SimulatedWorld):
            state = ("failed",)  # saved in checkpoints like the rest of the world

            def __init__(self, task: Any) -> None:
                super().__init__(task)
                self.failed = False

            def perform(self, step: Any) -> Any:
                if step.action == "pick" and not self.failed:
                    self.failed = True
                    with self._lock:
                        self.inject("action-failed", str(step), "the gripper slipped")
                        touched = self.model.ground(step).relevant_atoms(frozenset(self._facts))
                        return False, [(f, f in self._facts) for f in sorted(touched)]
                return super().perform(step)

        return World(task)


def planned_mission() -> Any:
    """An Executive over the rooms domain with symbolic skills and one failing pick."""
    from plan_bridge.execution.executive import Executive, ReplanPolicy
    from plan_bridge.execution.simulation import symbolic_skills
    from plan_bridge.pddl.task import load_task

    task = load_task(ROOMS / "domain.pddl", ROOMS / "problems" / "p01.pddl")
    world = PickFailsOnce.world(task)
    return Executive(
        task,
        symbolic_skills(world),
        "fast-downward",
        policy=ReplanPolicy.named("replan-only"),
    )
