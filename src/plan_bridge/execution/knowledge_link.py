"""An executive following a knowledge base (``Executive.attach_knowledge``).

The :class:`~plan_bridge.pddl.knowledge.KnowledgeBase` holds the problem; the
executive's belief holds its facts and values (one belief: skills' effects and
observations and the knowledge base's changes all update it). A change of the
knowledge base's objects or goal is news for the executive: it stops the plan in
force, and where the mission loop takes operator requests it takes the news,
rebuilds its task from the knowledge base and replans (one replan of the budget). A
fact or value the knowledge base changes is in the belief at once: the next step's
preconditions and the next replan see it, the plan in force goes on.

A knowledge base of a task view's whole world also learns the objects the robots see on
the way that nobody knew of (a new cup on a table): they join its instances (source
:data:`SEEN`), so that a goal may name them; that change needs no replan.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Collection, Mapping

from plan_bridge.belief import Belief
from plan_bridge.errors import PlanBridgeError
from plan_bridge.pddl.knowledge import KnowledgeBase, KnowledgeChange
from plan_bridge.pddl.task import Fact, PlanningTask

__all__ = ["SEEN", "KnowledgeLink"]

SEEN = "seen on the way"
"""The source of the instances a robot saw that the knowledge base did not hold."""


class KnowledgeLink:
    """The tie between one executive and its knowledge base.

    The belief takes the knowledge base's facts and values and holds them for it from
    now on. ``stop`` is called (from the changing thread) when the objects or the goal
    change; :meth:`take` gives what changed and the task to plan for.
    """

    def __init__(
        self,
        knowledge: KnowledgeBase,
        belief: Belief,
        task: PlanningTask,
        stop: Callable[[], None],
        *,
        whole_world: bool = False,
        objects_of: Callable[[Collection[Fact]], Mapping[str, str]] | None = None,
    ) -> None:
        self.knowledge = knowledge
        #: The knowledge base holds the whole world of a task view: the executive takes
        #: its goal, and the view makes the task (:meth:`take` builds none).
        self.whole_world = whole_world
        self._stop = stop
        self._lock = threading.Lock()
        self._news: list[str] = []
        #: The world's objects and their types, those the belief has that the world did
        #: not know included (a task view's :meth:`objects`); None: none are learned.
        self._objects_of = objects_of
        self._belief = belief
        belief.replace(knowledge.facts, knowledge.values)
        knowledge.use_facts(belief)
        knowledge.add_listener(self._changed)
        if objects_of is not None:
            belief.add_listener(self._seen)
        if not whole_world and not knowledge.describes(task):
            self._news.append("the executive's task is not the knowledge base's problem")

    @property
    def changed(self) -> bool:
        """Whether objects or goal changed since the last :meth:`take`."""
        return bool(self._news)

    def take(self) -> tuple[str, PlanningTask | None]:
        """What changed (``""``: nothing) and the task of the knowledge base's problem
        now (None when nothing changed, or when it holds a whole world)."""
        with self._lock:
            news, self._news = self._news, []
        if not news:
            return "", None
        shown = "; ".join(news[:5]) + (f"; and {len(news) - 5} more" if len(news) > 5 else "")
        return shown, None if self.whole_world else self.knowledge.task()

    def close(self) -> None:
        """Stop following: the knowledge base keeps a copy of the facts."""
        self.knowledge.remove_listener(self._changed)
        self._belief.remove_listener(self._seen)
        self.knowledge.use_facts(None)
        with self._lock:
            self._news = []

    def _seen(self) -> None:
        """Objects the belief has at a place that the knowledge base does not name join
        its instances, with the types the world gives them."""
        if self._objects_of is None:
            return
        facts = self._belief.facts
        known = self.knowledge.objects
        new = {f[1] for f in facts if f[0] == "at" and len(f) == 3 and f[1] not in known}
        if not new:
            return
        types = self._objects_of(facts)
        for name in sorted(new):
            if name in types:
                try:
                    self.knowledge.add_instance(name, types[name], source=SEEN)
                except PlanBridgeError:  # a type the domain does not have: not ours
                    continue

    def _changed(self, change: KnowledgeChange) -> None:
        # Facts and values are in the belief already; an object seen on the way changes
        # no goal (the view's next task holds it when a goal names it).
        if not change.changes_objects_or_goal or change.source == SEEN:
            return
        with self._lock:
            self._news.append(str(change))
        self._stop()
