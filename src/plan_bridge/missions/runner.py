"""The mission runner: the one place where a run is put together.

``plan-bridge run``, ``plan-bridge study``, the ROS path (``run --ros``) and the
Python API build a mission the same way: a loaded :class:`~.mission.Target`, its
:class:`~.mission.MissionSetup` (skills and :class:`~plan_bridge.execution.world.World`),
a planner, an :class:`~plan_bridge.execution.executive.Executive`, and optionally a
journal with checkpoints::

    from plan_bridge.missions.mission import load_target
    from plan_bridge.missions.runner import MissionOptions, prepare_mission

    mission = prepare_mission(load_target("domains/recharge"), MissionOptions(seed=3))
    mission.run()
    print(mission.figures())   # the numbers ``plan-bridge run --json`` prints

What differs between the callers is passed in, never re-implemented: the ROS path
gives the robot's setup (``setup=``), the CLI adds listeners, a viewer and a console
to :attr:`Mission.executive` before :meth:`Mission.run`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from plan_bridge.errors import PlanBridgeError, Terminated

if TYPE_CHECKING:  # (imported lazily: the CLI reads DEFAULT_FAIL_RATE at start-up)
    from plan_bridge.execution.executive import Executive
    from plan_bridge.execution.temporal import TimelineRecorder
    from plan_bridge.execution.world import World
    from plan_bridge.missions.target import MissionSetup, Target
    from plan_bridge.pddl.knowledge import KnowledgeBase
    from plan_bridge.planning.types import Planner
    from smach.introspection.journal import Journal

__all__ = ["DEFAULT_FAIL_RATE", "Mission", "MissionOptions", "prepare_mission"]

DEFAULT_FAIL_RATE = 0.2
"""The fault rate of a domain folder with its own skills when none is given: high
enough that a default run shows a fault and the recovery. Symbolic skills default to 0."""


@dataclass(frozen=True)
class MissionOptions:
    """How to run a mission (the options of ``plan-bridge run``, with its defaults)."""

    seed: int = 0
    fail_rate: float | None = None
    """Probability of faults in the simulated world; None: :data:`DEFAULT_FAIL_RATE`
    for a domain with its own skills, 0 for symbolic skills."""
    planner: str = "auto"
    policy: str = "full"
    max_replans: int | None = None
    """Planner calls after the first (None: the policy's)."""
    planner_timeout: float | None = None
    """Hard limit of one planner call, seconds (None: the policy's)."""
    concurrent: bool = False
    time_scale: float = 0.0
    """Wall seconds per simulated second of a simulated world (0: as fast as it goes)."""
    variant: str = ""
    """A variant of the domain's world (``plan-bridge study --variant``)."""
    orders: str | None = None
    """An orders file (:mod:`plan_bridge.orders.order_file`): the mission serves its
    orders as they arrive, instead of the target's goal."""
    orders_open: bool = False
    """Take live orders too (control API, viewer, ROS 2) until stopped; without an
    orders file, the mission waits for them."""

    def fail_rate_for(self, target: Target) -> float:
        """:attr:`fail_rate`, or its default for ``target`` when none was given."""
        if self.fail_rate is not None:
            return self.fail_rate
        return DEFAULT_FAIL_RATE if target.has_own_skills else 0.0


@dataclass
class Mission:
    """A mission put together and ready to :meth:`run`."""

    target: Target
    options: MissionOptions
    setup: MissionSetup
    executive: Executive
    fail_rate: float
    timeline: TimelineRecorder
    journal: Journal | None = None
    outcome: str | None = None
    error: str | None = None
    """A skill that broke its contract (undeclared key, bad outcome, exception): the
    error, naming the state path; the mission failed."""
    _closers: list[Callable[[], None]] = field(default_factory=list)

    @property
    def world(self) -> World | None:
        return self.executive.world

    @property
    def planner(self) -> Planner:
        return self.executive.planner

    def record(
        self,
        path: str,
        header: dict[str, Any],
        *,
        append: bool = False,
        exact: dict[str, Any] | None = None,
    ) -> Journal:
        """Write every event to the journal ``path``, with a checkpoint (the executive's
        state and the world's snapshot) after every succeeded step; ``exact`` header
        entries are written whole (``header``'s are cut like events' values)."""
        from smach.introspection.journal import Journal

        journal = self.journal = Journal(
            path, self.executive, header=header, exact_header=exact, append=append
        )
        world = self.world

        def write_checkpoint(state: dict[str, Any]) -> None:
            snapshot = world.snapshot() if world is not None else None
            journal.write_state("checkpoint", state=state, world=snapshot)

        self.executive.checkpoint = write_checkpoint
        return journal

    def resume(self, checkpoint: dict[str, Any]) -> None:
        """Continue from a checkpoint of :meth:`record` (world first, then the plan)."""
        world = self.world
        if checkpoint.get("world") is not None and world is not None:
            world.restore(checkpoint["world"])
            world.abandon_running()  # steps in progress stopped with the process
        self.executive.resume_from(checkpoint["state"])

    def attach_knowledge(self, knowledge: KnowledgeBase | None = None) -> KnowledgeBase:
        """Let the mission follow a knowledge base (by default a new one holding the
        target's problem): its facts are the belief, a change of its objects or goal
        replans (``Executive.attach_knowledge``; serve it over ROS 2 with
        ``RobotConnection.serve_knowledge``). Returns it."""
        from plan_bridge.pddl.knowledge import KnowledgeBase

        view = self.executive.task_view
        if knowledge is None and view is not None:
            # The whole world the view knows, not the one plan's task.
            belief = self.executive.belief.facts
            knowledge = KnowledgeBase.from_task(
                self.executive.task, objects=view.objects(), facts=belief, values=belief.values
            )
        elif knowledge is None:
            knowledge = KnowledgeBase.from_task(self.executive.task)
        self.executive.attach_knowledge(knowledge)
        return knowledge

    def on_close(self, close: Callable[[], None]) -> None:
        """Call ``close`` when the run ends (before the journal's last record)."""
        self._closers.append(close)

    def run(self) -> str | None:
        """Execute the mission; the outcome (None when a skill broke its contract).

        The journal ends with a ``summary`` record, or with ``interrupted`` when Ctrl-C
        or SIGTERM stopped the run (then a resume continues it).
        """
        from plan_bridge.execution.events import WorldScenes
        from smach import SmachError

        interrupted: KeyboardInterrupt | None = None
        # Pictures of the world (``scene`` events) when it draws itself and a journal or a
        # viewer watches; attached last, so they follow the step ends they picture.
        scenes = WorldScenes.start(self.executive, self.world)
        try:
            self.outcome = self.executive.execute()
        except KeyboardInterrupt as exc:
            interrupted = exc
            raise
        except SmachError as exc:
            self.outcome, self.error = None, str(exc)
            self.executive.report.explanation = str(exc)
        finally:
            if scenes is not None:
                scenes.close()
            for close in reversed(self._closers):
                close()
            self._closers.clear()
            journal = self.journal
            if journal is not None:
                if interrupted is None:
                    journal.write_record("summary", **self.executive.report.to_json())
                else:
                    by = "SIGTERM" if isinstance(interrupted, Terminated) else "SIGINT"
                    journal.write_raw("interrupted", signal=by)
                journal.close()
        return self.outcome

    @property
    def goal_reached(self) -> bool:
        return self.executive.report.goal_reached

    def figures(self) -> dict[str, Any]:
        """The run's numbers: what ``plan-bridge run --json`` prints."""
        report = self.executive.report
        data: dict[str, Any] = {
            "target": self.target.name,
            "problem": self.target.problem_path.name,
            "seed": self.options.seed,
            "fail_rate": self.fail_rate,
            "planner": self.planner.name,
            **report.to_json(),
        }
        timeline = self.timeline
        if timeline.temporal:
            data["makespan_planned"] = timeline.makespan_planned
            executed = timeline.makespan_executed
            data["makespan_executed"] = None if executed is None else round(executed, 4)
        if self.world is not None:
            data.update(
                (key, value) for key, value in self.world.figures().items() if value is not None
            )
        data.update(self.target.figures())
        return data


def prepare_mission(
    target: Target,
    options: MissionOptions = MissionOptions(),
    *,
    setup: MissionSetup | None = None,
    planner: Planner | None = None,
) -> Mission:
    """Put a mission together: skills and world (the target's, or ``setup``), planner,
    policy, executive. Raises :class:`~plan_bridge.errors.PlanBridgeError` (with what
    is wrong and where) for a bad option or skills that do not fit the domain."""
    from plan_bridge.execution.executive import Executive
    from plan_bridge.execution.policy import ReplanPolicy
    from plan_bridge.execution.temporal import TimelineRecorder
    from plan_bridge.planning.planner import get_planner

    try:
        policy = ReplanPolicy.named(options.policy)
    except ValueError as exc:
        raise MissionError(str(exc)) from exc
    if options.max_replans is not None:
        policy = replace(policy, max_replans=options.max_replans)
    if options.planner_timeout is not None:
        policy = replace(policy, planner_timeout=options.planner_timeout)
    fail_rate = options.fail_rate_for(target)
    if setup is None:
        setup = target.setup(seed=options.seed, fail_rate=fail_rate, variant=options.variant)
    problems = setup.skills.check(target.task)
    if problems:
        raise MissionError("the skills do not fit the domain:\n  " + "\n  ".join(problems))
    chosen = planner if planner is not None else get_planner(options.planner)
    if setup.planner_for is not None:
        chosen = setup.planner_for(chosen)
    settings: dict[str, Any] = {
        "world": setup.world,
        "policy": policy,
        "sense": setup.sense,
        "concurrent": setup.concurrent or options.concurrent,
        "task_view": setup.task_view,
    }
    executive: Executive
    if options.orders is not None or options.orders_open:
        from plan_bridge.orders.book import OrderBook
        from plan_bridge.orders.order_executive import OrderExecutive
        from plan_bridge.orders.order_file import load_orders

        scheduled = load_orders(options.orders).draw(options.seed) if options.orders else []
        book = OrderBook(scheduled, closed=not options.orders_open)
        executive = OrderExecutive(
            target.task,
            setup.skills,
            chosen,
            orders=book,
            goal_of=target.read_order_goal,
            upkeep=target.upkeep_goals,
            **settings,
        )
    else:
        executive = Executive(target.task, setup.skills, chosen, **settings)
    world = executive.world
    if world is not None:
        world.time_scale = options.time_scale
    timeline = TimelineRecorder()
    executive.add_listener(timeline)
    return Mission(target, options, setup, executive, fail_rate, timeline)


class MissionError(PlanBridgeError):
    """A mission cannot be put together (a bad option, skills that do not fit)."""
