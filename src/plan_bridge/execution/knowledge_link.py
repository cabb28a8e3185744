"""An executive following a knowledge base (``Executive.attach_knowledge``).

The :class:`~plan_bridge.pddl.knowledge.KnowledgeBase` holds the problem; the
executive's belief holds its facts and values (one belief: skills' effects and
observations and the knowledge base's changes all update it). A change of the
knowledge base's objects or goal is news for the executive: it stops the plan in
force, and where the mission loop takes operator requests it takes the news,
rebuilds its task from the knowledge base and replans (one replan of the budget). A
fact or value the knowledge base changes is in the belief at once: the next step's
preconditions and the next replan see it, the plan in force goes on.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

from plan_bridge.belief import Belief
from plan_bridge.pddl.knowledge import KnowledgeBase, KnowledgeChange
from plan_bridge.pddl.task import PlanningTask

__all__ = ["KnowledgeLink"]


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
    ) -> None:
        self.knowledge = knowledge
        #: The knowledge base holds the whole world of a task view: the executive takes
        #: its goal, and the view makes the task (:meth:`take` builds none).
        self.whole_world = whole_world
        self._stop = stop
        self._lock = threading.Lock()
        self._news: list[str] = []
        belief.replace(knowledge.facts, knowledge.values)
        knowledge.use_facts(belief)
        knowledge.add_listener(self._changed)
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
        self.knowledge.use_facts(None)
        with self._lock:
            self._news = []

    def _changed(self, change: KnowledgeChange) -> None:
        if not change.changes_objects_or_goal:
            return  # facts and values are in the belief already
        with self._lock:
            self._news.append(str(change))
        self._stop()
