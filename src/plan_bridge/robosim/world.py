"""A pyrobosim world as the :class:`~plan_bridge.execution.world.World` of a mission.

**Time.** Simulated seconds on the world's :class:`~plan_bridge.execution.clock.SimClock`,
spent by what the robots do: a drive takes its trajectory's time (path length at the
path executor's speed, turns included), the other actions fixed durations
(:data:`~.results.ACTION_SECONDS`, the domain's). pyrobosim runs as fast as the CPU allows
(``realtime_factor=-1``); with ``time_scale > 0`` drives run at ``1 / time_scale`` of
real time and the other actions wait their paced time, so a viewer can follow (and a
preempt stops a drive half-way).

**Faults** are pyrobosim's own: every action of every robot gets
``ExecutionOptions(success_probability=1 - fail_rate, rng_seed=...)`` seeded from the
run's seed (its battery usage is the world file's), and numpy's generator (paths,
grasps, placements) is seeded before every action, so a seeded run repeats.

**Sensing** reports what a robot can observe where it is: its own place (of the map,
:mod:`plan_bridge.maps`), what it holds, its battery, the open/locked state of the
hallways and locations of its room that the step is about and of those it stands
at, and the objects of the spawns it stands at (what pyrobosim's ``detect`` sees
there, when the location is open) - never the planner's effects read back. What the
robots saw of the hallways is also what their drives route over
(:meth:`RobosimWorld.closed_halls`).

**Events** (:mod:`.events`) are applied when the clock passes their time: at each
action's start and end, and during a drive (which stops where the robot is at that
time; if its remaining path is blocked the drive fails there).
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from plan_bridge.belief import Observation
from plan_bridge.execution.clock import SimClock
from plan_bridge.maps.graph import PlaceMap
from plan_bridge.maps.model import WorldModel
from plan_bridge.pddl.task import Fact, format_fact, parse_fact
from plan_bridge.robosim.adopt import adopt_step, restore_world, snapshot_world
from plan_bridge.robosim.description import describe_world, robot_place
from plan_bridge.robosim.events import WorldEvent, check_events
from plan_bridge.robosim.loading import load_world_file, quiet_stdout
from plan_bridge.robosim.picture import TRAIL_CHUNK, scene_picture
from plan_bridge.robosim.results import ActionResult

if TYPE_CHECKING:
    from plan_bridge.planning.types import PlanStep

__all__ = ["TRAIL_POINTS", "RobosimWorld"]

#: The robot actions that get seeded ExecutionOptions (faults).
FAULTY = ("navigate", "pick", "place", "detect", "open", "close", "charge")
#: Poses a robot's trail keeps (about; the newest): a mission's drives whole, the last
#: part of a day's. They are dropped a picture's line at a time (``TRAIL_CHUNK``).
TRAIL_POINTS = 3000


class RobosimWorld:
    """The world of a mission on a pyrobosim world file (see the module's doc)."""

    def __init__(
        self,
        world_file: str | Path,
        goal: Iterable[Fact] = (),
        *,
        seed: int = 0,
        fail_rate: float = 0.0,
        events: Iterable[WorldEvent] = (),
        loaded: tuple[Any, WorldModel] | None = None,
    ) -> None:
        if not 0.0 <= fail_rate <= 1.0:
            raise ValueError(f"fail_rate must be between 0 and 1, got {fail_rate}")
        self.path = Path(world_file)
        if loaded is not None:  # the pyrobosim world just loaded for the task, unchanged
            self.sim, self.model = loaded
        else:
            self.sim = load_world_file(self.path)
            self.model = describe_world(self.sim, str(self.path))
        #: The map of places the drives route over.
        self.map = PlaceMap(self.model)
        #: Whether each hallway is open, as the robots last saw it (the world file's
        #: state at the start): the routes a drive takes avoid those seen closed.
        self.seen_open: dict[str, bool] = {
            hall: self.model.gates[hall].is_open for hall in self.model.halls
        }
        #: Each robot's drives: the hallways crossed, in order (for reports and tests).
        self.crossed: dict[str, list[str]] = {r.name: [] for r in self.sim.robots}
        self.goal = tuple(parse_fact(f) for f in goal)
        self.seed = seed
        self.fail_rate = fail_rate
        self.clock = SimClock()
        self._time_scale = 0.0
        self._lock = threading.RLock()
        self._timeline = threading.local()
        self._names = {name.lower(): name for name in self.model.names}
        self.robots: dict[str, Any] = {robot.name.lower(): robot for robot in self.sim.robots}
        self.actions_run = 0
        self.faults = 0
        self.distance_m = 0.0
        """Metres the robots drove (their executed paths, stops on the way included)."""
        self.trails: dict[str, list[list[list[float]]]] = {r.name: [] for r in self.sim.robots}
        """Each robot's executed drives: polylines of ``[x, y]`` points (metres), one per
        stretch driven without a jump (for :mod:`.picture`; kept in snapshots)."""
        self.battery_start = {r.name: float(r.battery_level) for r in self.sim.robots}
        self.charged: dict[str, float] = dict.fromkeys(self.battery_start, 0.0)
        """Battery (percent) each robot's charges put back."""
        #: Wall seconds spent inside pyrobosim (path planning, actions): for benchmarks.
        self.robot_wall_s = 0.0
        self.searched: set[str] = set()
        self.changes: list[str] = []
        """What the world's events did (and when), in order."""
        self._pending: list[WorldEvent] = []
        self._options: dict[tuple[str, str], Any] = {}
        self._install_options()
        self.schedule(events)

    # -- set-up ------------------------------------------------------------------------
    def _install_options(self) -> None:
        from pyrobosim.planning.actions import ExecutionOptions

        for index, robot in enumerate(self.sim.robots):
            own = dict(robot.action_execution_options)
            for number, action in enumerate(FAULTY):
                usage = own[action].battery_usage if action in own else 0.0
                options = ExecutionOptions(
                    success_probability=1.0 - self.fail_rate,
                    rng_seed=(self.seed * 1009 + index * 31 + number) % 2**32,
                    battery_usage=usage,
                )
                self._options[(robot.name, action)] = options
                if action != "charge":
                    own[action] = options
            robot.action_execution_options = own

    def schedule(self, events: Iterable[WorldEvent]) -> None:
        """Add events (their names are checked against the world: :class:`EventError`);
        a time window is drawn from the run's seed."""
        new = [event.drawn(self.seed) for event in events]
        check_events(new, self.model.gates, self.model.items, self.spawn_names())
        with self._lock:
            self._pending = sorted([*self._pending, *new], key=lambda e: e.at)

    @property
    def time_scale(self) -> float:
        """Wall seconds per simulated second (0: as fast as the CPU allows)."""
        return self._time_scale

    @time_scale.setter
    def time_scale(self, value: float) -> None:
        if value < 0:
            raise ValueError(f"time_scale must be 0 or more, got {value!r}")
        self._time_scale = float(value)

    @property
    def realtime_factor(self) -> float:
        return -1.0 if self._time_scale <= 0 else 1.0 / self._time_scale

    def name(self, pddl: str) -> str:
        """The world's name of a PDDL object (PDDL names are read in lower case)."""
        return self._names.get(pddl.lower(), pddl)

    # -- time and events -------------------------------------------------------------
    def now(self) -> float:
        return float(self.clock.now())

    def elapse(self, seconds: float) -> None:
        """The calling thread's action took ``seconds`` of simulated time (in
        :meth:`own_timeline`, on the thread's own timeline)."""
        at = getattr(self._timeline, "at", None)
        if seconds <= 0:
            pass
        elif self.clock.taking_part():
            self.clock.sleep(seconds)
        elif at is None:
            self.clock.advance(seconds)
        else:
            self._timeline.at = at + seconds
            with self._lock:
                self.clock.advance(self._timeline.at - self.clock.now())

    @contextlib.contextmanager
    def own_timeline(self) -> Iterator[None]:
        """The calling thread's actions on a timeline of their own, from now (the clock
        at the end of the latest of them): robots acting at once from threads that take
        no turns (a world node's) overlap in time instead of adding up."""
        self._timeline.at = self.now()
        try:
            yield
        finally:
            self._timeline.at = None

    def next_event_time(self) -> float | None:
        with self._lock:
            return self._pending[0].at if self._pending else None

    def apply_due_events(self) -> list[str]:
        """Apply the events whose time has come; what each did. An event the world
        refuses now (a robot in the hallway being closed) waits for the next check, and
        so do the later events on the same hallway or location (a lock waits for the
        close before it)."""
        done: list[str] = []
        with self._lock:
            now = self.now()
            kept: list[WorldEvent] = []
            waiting: set[str] = set()  # targets with an earlier event still waiting
            for event in self._pending:
                if event.at > now + 1e-9 or event.target in waiting:
                    kept.append(event)
                    continue
                ok, text = self._apply_event(event)
                if ok:
                    done.append(f"{now:.2f} s: {text}")
                else:
                    kept.append(event)
                    waiting.add(event.target)
            self._pending = kept
            self.changes.extend(done)
        if done and self.on_scene is not None:  # the viewer's picture (see on_scene)
            self.on_scene("; ".join(done))
        return done

    def _apply_event(self, event: WorldEvent) -> tuple[bool, str]:
        world = self.sim
        if event.kind == "move":
            obj = world.get_object_by_name(event.target)
            if obj is None or any(r.manipulated_object is obj for r in world.robots):
                return True, f"{event.target} is held by a robot: not moved ({event.origin})"
            ok = bool(world.update_object(obj, loc=event.to))
            return ok, f"{event.target} moved to {obj.parent.name}"
        if event.kind == "remove":
            obj = world.get_object_by_name(event.target)
            if obj is None:
                return True, f"remove {event.target}: no such object ({event.origin})"
            if any(r.manipulated_object is obj for r in world.robots):
                return True, f"{event.target} is held by a robot: not removed ({event.origin})"
            with self.quietly():
                world.remove_object(obj, show=False)
            return True, f"{event.target} removed"
        if event.kind == "add":
            with self.quietly():
                added = world.add_object(
                    name=event.target, category=event.category, parent=event.to, show=False
                )
            if added is None:
                return True, f"add {event.target}: no room on {event.to} ({event.origin})"
            return True, f"{event.target} ({event.category}) added on {added.parent.name}"
        if event.kind in ("close", "lock") and any(
            robot.location is not None and robot.location.name == event.target
            for robot in world.robots
        ):
            return False, ""  # a robot in the doorway: try again later (quietly)
        call = {
            "open": world.open_location,
            "close": world.close_location,
            "lock": world.lock_location,
            "unlock": world.unlock_location,
        }[event.kind]
        result = call(event.target)
        if result.status.name == "SUCCESS":
            for robot in world.robots:
                robot.update_polygons()
            return True, f"{event.target} {event.kind}{'ed' if event.kind != 'close' else 'd'}"
        if "Robot" in str(result.message):  # a robot in the doorway: try again later
            return False, ""
        return True, f"{event.kind} {event.target}: {result.message} ({event.origin})"

    # -- running robot actions -------------------------------------------------------
    def robot(self, name: str) -> Any:
        robot = self.robots.get(name.lower())
        if robot is None:
            raise KeyError(f"no robot {name!r} in {self.model.name}")
        return robot

    def begin(self, robot: Any) -> None:
        """Before an action: seed numpy's generator (paths, grasps, placements) from the
        run's seed and the action's number, and apply the events that are due."""
        import numpy as np

        with self._lock:
            self.actions_run += 1
            np.random.seed((self.seed * 1_000_003 + self.actions_run) % 2**32)
        self.apply_due_events()

    def run_blocking(
        self, robot: Any, call: Callable[[], Any], preempted: Callable[[], bool]
    ) -> ActionResult:
        """Run a blocking pyrobosim call in a worker thread; a preempt cancels the
        robot's action (``robot.cancel_actions()``)."""
        if preempted():
            return ActionResult("CANCELED", "preempted before it started")
        box: dict[str, Any] = {}

        def work() -> None:
            try:
                box["result"] = call()
            except Exception as exc:  # reported as the action's failure, not lost
                box["error"] = exc

        began = time.perf_counter()
        worker = threading.Thread(target=work, name=f"pyrobosim-{robot.name}", daemon=True)
        worker.start()
        canceled = False
        while worker.is_alive():
            worker.join(0.02)
            if not canceled and worker.is_alive() and preempted():
                canceled = True
                if robot.is_busy():
                    robot.cancel_actions()
        self.robot_wall_s += time.perf_counter() - began
        if "error" in box:
            error = box["error"]
            return ActionResult("EXECUTION_FAILURE", f"{type(error).__name__}: {error}")
        result = ActionResult.of(box["result"])
        if result.message.startswith("Simulated"):
            with self._lock:
                self.faults += 1
        if canceled and result.status != "SUCCESS":
            return ActionResult("CANCELED", result.message or "canceled")
        return result

    def wait_paced(self, seconds: float, preempted: Callable[[], bool]) -> bool:
        """With a time scale, wait the wall time of ``seconds``; False if preempted."""
        deadline = time.monotonic() + seconds * self._time_scale
        while time.monotonic() < deadline:
            if preempted():
                return False
            time.sleep(min(0.02, max(0.0, deadline - time.monotonic())))
        return not preempted()

    def draw_fault(self, robot: Any, action: str) -> bool:
        """Whether ``action`` (one pyrobosim has no options for) fails now."""
        failed = not self._options[(robot.name, action)].should_succeed()
        if failed:
            with self._lock:
                self.faults += 1
        return failed

    def spawn_names(self) -> list[str]:
        """Every object spawn of the world."""
        return [spawn for gate in self.model.gates.values() for spawn in gate.spawns]

    # -- what a robot sees -----------------------------------------------------------
    def spot_of(self, robot: Any) -> str:
        """The place a robot is at (the nearest place of its room when it stands between
        places; of its hallway's doorways in a hallway)."""
        return robot_place(self.model, robot)

    def closed_halls(self) -> set[str]:
        """The hallways the robots last saw closed (a drive routes round them)."""
        return {hall for hall, is_open in self.seen_open.items() if not is_open}

    def observe(self, robot: Any, about: Iterable[str] = ()) -> list[Observation]:
        """What ``robot`` sees now, of itself and of the things ``about`` names."""
        model = self.model
        named = {self.name(n) for n in about}
        spot = self.spot_of(robot)
        seen: dict[Fact, bool | float] = {}
        me = robot.name
        if spot:
            seen[_f("At", me, spot)] = True
        for name in named:
            if name in model.places and name != spot:
                seen[_f("At", me, name)] = False
        held = robot.manipulated_object
        for item in {*(n for n in named if n in model.items), *([held.name] if held else [])}:
            seen[_f("Holding", me, item)] = held is not None and held.name == item
        seen[_f("HandEmpty", me)] = held is None
        seen[_f("battery-level", me)] = round(float(robot.battery_level), 3)
        place = model.places.get(spot)
        room = place.room if place is not None else ""
        gates = {n for n in named if n in model.gates}
        gates |= {g for n in {*named, spot} if n in model.places for g in model.places[n].gates}
        for gate in sorted(gates):
            if self._visible(gate, room, spot):
                entity = self.sim.get_entity_by_name(gate)
                seen[_f("IsOpen", gate)] = bool(entity.is_open)
                seen[_f("IsLocked", gate)] = bool(entity.is_locked)
                if gate in self.seen_open:
                    self.seen_open[gate] = bool(entity.is_open)
        if place is not None and place.fixture is not None:
            self._look_at_spawns(place.name, place.spawns, place.fixture, seen)
        return sorted(seen.items(), key=lambda pair: pair[0])

    def _look_at_spawns(
        self, place: str, spawns: Sequence[str], fixture: str, seen: dict[Fact, bool | float]
    ) -> None:
        """The objects on the spawns reached from ``place`` (none when the location is
        closed: the robot cannot see inside)."""
        location = self.sim.get_entity_by_name(fixture)
        if location is None or not location.is_open:
            return
        here: set[str] = set()
        for name in spawns:
            entity = self.sim.get_entity_by_name(name)
            if entity is not None:
                here |= {child.name for child in entity.children}
                for child in entity.children:
                    if child.name not in self.model.items:
                        self.learn_object(child.name, name, str(child.category or ""))
        single = len(self.model.gates[fixture].spawns) == 1
        for item in self.model.items:
            seen[_f("At", item, place)] = item in here
            if item in here or single:
                seen[_f("Has", fixture, item)] = item in here

    def learn_object(self, name: str, spawn: str | None, category: str) -> None:
        """An object the robots had never heard of (seen at a spawn): it joins the map's
        objects, so sensing reports it and goals may name it."""
        with self._lock:
            self.model.items.setdefault(name, spawn)
            self.model.item_categories.setdefault(name, category)
            self._names[name.lower()] = name

    def _visible(self, gate: str, room: str, spot: str) -> bool:
        place = self.model.places.get(spot)
        if place is not None and gate in place.gates:
            return True
        entity = self.sim.get_entity_by_name(gate)
        if self.model.gates[gate].kind == "hall":
            return room in (entity.room_start.name, entity.room_end.name)
        return entity.parent is not None and entity.parent.name == room

    # -- the World protocol ------------------------------------------------------------
    def sense(self, steps: Sequence[PlanStep]) -> list[Observation]:
        """What the robots of ``steps`` see now of the things the steps name."""
        seen: dict[Fact, bool | float] = {}
        for step in steps:
            for arg in step.arguments:
                robot = self.robots.get(arg.lower())
                if robot is not None:
                    seen.update(self.observe(robot, step.arguments))
        return sorted(seen.items(), key=lambda pair: pair[0])

    def adopt(self, step: PlanStep, observations: Sequence[Observation]) -> None:
        """A user's skill did ``step``: make the pyrobosim world agree, then take the
        observations it can (robot and object places, open/locked, battery)."""
        with self._lock:
            self.actions_run += 1
            adopt_step(self, step, observations)

    @property
    def faults_injected(self) -> int:
        return self.faults

    def truth(self, fact: Fact) -> bool:
        """Whether a fact of the domain holds in the pyrobosim world."""
        name, *args = fact
        name = name.lower()
        names = [self.name(a) for a in args]
        world = self.sim
        if name == "at":
            robot = self.robots.get(args[0].lower())
            if robot is not None:
                return self.spot_of(robot) == names[1]
            obj = world.get_object_by_name(names[0])
            spawn = obj.parent if obj is not None else None
            return spawn is not None and self.model.spawn_place(spawn.name) == names[1]
        if name == "holding":
            held = self.robot(args[0]).manipulated_object
            return held is not None and held.name == names[1]
        if name == "handempty":
            return self.robot(args[0]).manipulated_object is None
        if name in ("isopen", "islocked"):
            entity = world.get_entity_by_name(names[0])
            return bool(entity.is_open if name == "isopen" else entity.is_locked)
        if name == "has":
            obj = world.get_object_by_name(names[1])
            spawn = obj.parent if obj is not None else None
            return spawn is not None and spawn.parent is not None and spawn.parent.name == names[0]
        if name == "searched":
            return names[0] in self.searched
        raise ValueError(f"{format_fact(fact)}: not a goal predicate of the robosim domain")

    def goal_reached(self) -> bool:
        with self._lock:
            return all(self.truth(atom) for atom in self.goal)

    def snapshot(self) -> dict[str, Any]:
        with self._lock:
            return snapshot_world(self, self._options, self._pending)

    def restore(self, data: dict[str, Any]) -> None:
        with self._lock:
            self._pending = restore_world(self, data, self._options)

    def abandon_running(self) -> None:
        """Nothing to undo: a checkpoint is taken between actions, and the restored
        world holds the robots where they were then."""

    def figures(self) -> dict[str, Any]:
        return {
            "sim_time_s": round(self.now(), 3),
            "faults_injected": self.faults,
            "actions_run": self.actions_run,
            "distance_m": round(self.distance_m, 3),
            "battery": {r.name: round(float(r.battery_level), 2) for r in self.sim.robots},
            "battery_used": round(self.battery_used(), 3),
            "world_changes": len(self.changes),
        }

    def battery_used(self) -> float:
        """Battery the robots used (percentage points, summed over the robots): what
        they had at the start minus what they have now, plus what charging put back."""
        return sum(
            self.battery_start[r.name] - float(r.battery_level) + self.charged[r.name]
            for r in self.sim.robots
        )

    def recharge(self, robot: Any) -> None:
        """A charge: the robot's battery to 100 (what it put back is counted)."""
        with self._lock:
            self.charged[robot.name] += max(0.0, 100.0 - float(robot.battery_level))
            robot.battery_level = 100.0

    def count_drive(self, robot: Any, level_before: float, metres: float) -> None:
        """After a drive of ``metres``: pyrobosim charges a robot that arrives at a
        charger's spawn (battery to 100); count what that put back."""
        usage = float(self._options[(robot.name, "navigate")].battery_usage)
        expected = max(0.0, level_before - usage * metres)
        level = float(robot.battery_level)
        if level > expected + 1e-6:
            with self._lock:
                self.charged[robot.name] += level - expected

    def record_drive(self, robot: Any, points: Iterable[Any]) -> None:
        """Add the poses a robot passed (``.x``, ``.y``) to its trail: continuing its last
        stretch when they start where it ended, else as a new one."""
        xy = [[round(float(p.x), 3), round(float(p.y), 3)] for p in points]
        xy = [p for i, p in enumerate(xy) if i == 0 or p != xy[i - 1]]
        if len(xy) < 2:
            return
        with self._lock:
            trail = self.trails.setdefault(robot.name, [])
            if trail and math.dist(trail[-1][-1], xy[0]) < 0.05:
                trail[-1].extend(xy[1:])
            else:
                trail.append(xy)
            # A day's drives would make pictures and checkpoints grow without end: the
            # trail keeps about the robot's last TRAIL_POINTS poses, dropped in whole
            # chunks of TRAIL_CHUNK (a picture draws a trail a chunk a line: the lines
            # kept stay the same, and a journal writes a picture's changed lines only).
            extra = sum(len(part) for part in trail) - TRAIL_POINTS
            while extra > 0 and trail:
                cut = -(-extra // TRAIL_CHUNK) * TRAIL_CHUNK
                if len(trail[0]) - cut >= 2:
                    del trail[0][:cut]
                    break
                extra -= len(trail.pop(0))

    # -- the viewer's picture (a "scene" event; plan_bridge.execution.events.WorldScenes) --
    on_scene: Callable[[str], object] | None = None
    """Set by whoever shows the world (the mission runner, for a journal or a viewer):
    called, with what changed, when the world's events changed it."""

    def scene(self) -> tuple[str, str]:
        """The picture of the world now, for viewers: (SVG text, caption)."""
        return scene_picture(self)

    # -- end of the viewer's picture ------------------------------------------------------

    def close(self) -> None:
        """Stop pyrobosim's threads (sensors, path validation)."""
        for robot in self.sim.robots:
            robot.stop_sensor_threads()

    def quietly(self) -> Any:
        """A context in which pyrobosim's prints are swallowed."""
        return quiet_stdout()


def _f(*words: str) -> Fact:
    return tuple(word.lower() for word in words)
