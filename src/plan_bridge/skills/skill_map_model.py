"""The data of a skill map (:mod:`~plan_bridge.skills.skill_map`): its entries, the
argument picks, its problems and :class:`SkillMap.apply`.

Both :mod:`~plan_bridge.skills.skill_map` (which loads a map) and
:mod:`~plan_bridge.skills.skill_map_checks` (which checks and resolves one) build on
these types; neither imports the other's back.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from plan_bridge.errors import PlanBridgeError
from plan_bridge.skills.registry import Skill, SkillFactory, SkillRegistry
from plan_bridge.skills.skill_map_source import factory_name, parameter_identifier

if TYPE_CHECKING:
    import smach
    from plan_bridge.pddl.task import ActionSchema
    from plan_bridge.skills.ros.entries import RosEntry

__all__ = [
    "ENTRY_KEYS",
    "MAP_FILE",
    "ConstantPick",
    "HasActions",
    "MapProblem",
    "ParameterPick",
    "SelectedArguments",
    "SkillMap",
    "SkillMapEntry",
    "SkillMapError",
    "describe_factory",
    "registered_skill",
]

#: The name of a domain folder's skill map.
MAP_FILE = "skills.toml"
#: The keys an entry may have.
ENTRY_KEYS = ("factory", "arguments", "outcome_map", "variant")

Constant = str | int | float | bool
"""A constant in ``arguments``: passed to the factory as it is."""


class HasActions(Protocol):
    """What a map is checked against: the domain's actions (a
    :class:`~plan_bridge.pddl.task.PlanningTask` has them)."""

    @property
    def actions(self) -> Mapping[str, ActionSchema]: ...


# -- errors ---------------------------------------------------------------------------


@dataclass(frozen=True)
class MapProblem:
    """One problem of a skill map, at ``path:line`` (``line`` None: the whole file)."""

    path: str
    line: int | None
    message: str
    column: int | None = None

    @property
    def location(self) -> str:
        parts = [self.path]
        if self.line is not None:
            parts.append(str(self.line))
            if self.column is not None:
                parts.append(str(self.column))
        return ":".join(parts)

    def __str__(self) -> str:
        return f"{self.location}: {self.message}"


class SkillMapError(PlanBridgeError):
    """A skill map that cannot be used: every problem found, each with its ``file:line``."""

    def __init__(self, problems: Sequence[MapProblem]) -> None:
        if not problems:
            raise ValueError("a SkillMapError needs at least one problem")
        self.problems = tuple(problems)
        super().__init__(self._render())

    @property
    def path(self) -> str:
        return self.problems[0].path

    @property
    def line(self) -> int | None:
        return self.problems[0].line

    def _render(self) -> str:
        if len(self.problems) == 1:
            return str(self.problems[0])
        listed = "\n  ".join(str(problem) for problem in self.problems)
        return f"{len(self.problems)} problems in the skill map {self.path}:\n  {listed}"

    def __reduce__(self) -> tuple[object, ...]:
        return (type(self), (self.problems,))


# -- the map ----------------------------------------------------------------------------


@dataclass(frozen=True)
class ParameterPick:
    """In ``arguments``: the action's parameter at ``index`` (``"?to"``)."""

    index: int


@dataclass(frozen=True)
class ConstantPick:
    """In ``arguments``: a constant, passed as it is."""

    value: Constant


class SelectedArguments:
    """A factory called with some of the action's arguments, and constants
    (``arguments = ["?to", "fast"]``): ``selected("r1", "hall", "kitchen")`` calls
    ``factory("kitchen", "fast")``.

    Its signature takes the action's parameters, so :meth:`SkillRegistry.check`
    checks it like any factory; ``__qualname__`` is the factory's, for messages.
    """

    def __init__(
        self,
        factory: SkillFactory,
        picks: Sequence[ParameterPick | ConstantPick],
        parameters: Sequence[str],
        shown: Sequence[str],
    ) -> None:
        self.factory = factory
        self.picks = tuple(picks)
        self.shown = tuple(shown)
        """The ``arguments`` as written in the map."""
        self.__signature__ = inspect.Signature(
            [
                inspect.Parameter(parameter_identifier(name, i), inspect.Parameter.POSITIONAL_ONLY)
                for i, name in enumerate(parameters)
            ]
        )
        self.__qualname__ = factory_name(factory)
        self.__name__ = getattr(factory, "__name__", self.__qualname__)
        self.__module__ = getattr(factory, "__module__", None) or __name__
        self._arity = len(parameters)

    def __call__(self, *arguments: str) -> smach.State:
        if len(arguments) != self._arity:
            raise TypeError(
                f"{self.__qualname__}: the action has {self._arity} parameter(s), got "
                f"{len(arguments)} argument(s)"
            )
        values = [
            arguments[pick.index] if isinstance(pick, ParameterPick) else pick.value
            for pick in self.picks
        ]
        return self.factory(*values)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, SelectedArguments):
            return NotImplemented
        return (self.factory, self.picks, self._arity) == (other.factory, other.picks, other._arity)

    def __hash__(self) -> int:
        return hash((self.factory, self.picks, self._arity))

    def __repr__(self) -> str:
        return f"<{self.__qualname__}({', '.join(self.shown)})>"


@dataclass(frozen=True)
class SkillMapEntry:
    """One action (or variant) of a skill map, resolved."""

    action: str
    """The action's name, as in the domain."""
    target: str
    """The factory as written: ``"module:callable"``."""
    factory: SkillFactory
    """What is registered: the factory, or a :class:`SelectedArguments` around it."""
    path: Path
    line: int | None
    arguments: tuple[Constant, ...] | None = None
    """``arguments`` as written; None: all of the action's, in PDDL order."""
    outcome_map: Mapping[str, str] = field(default_factory=dict)
    variant: str = ""
    ros: RosEntry | None = None
    """For an entry with ``ros_action``, ``ros_service`` or ``ros_topic``: what it calls
    (:mod:`~plan_bridge.skills.ros.entries`); ``target`` is then ``"ros_action NAME"``."""

    @property
    def location(self) -> str:
        """``path/skills.toml:LINE``."""
        return f"{self.path}:{self.line}" if self.line is not None else str(self.path)

    @property
    def label(self) -> str:
        """``[action]``, or ``[action] variant "name"``, for messages."""
        return f"[{self.action}]" + (f" variant {self.variant!r}" if self.variant else "")


@dataclass(frozen=True)
class SkillMap:
    """The entries of a ``skills.toml``, checked against a domain's actions."""

    path: Path
    entries: tuple[SkillMapEntry, ...] = ()

    def entry(self, action: str, variant: str = "") -> SkillMapEntry | None:
        """The entry for ``action`` (or one of its variants), or None."""
        name = action.lower()
        for entry in self.entries:
            if entry.action.lower() == name and entry.variant == variant:
                return entry
        return None

    @property
    def actions(self) -> list[str]:
        """The actions the map gives a main skill to."""
        return sorted({entry.action for entry in self.entries if not entry.variant})

    def apply(self, registry: SkillRegistry, *, registered_by: str = "") -> SkillRegistry:
        """Register every entry in ``registry`` as the user's own skill (not simulated).

        An entry for an action (or variant) whose skill in ``registry`` is a simulated
        one (a domain's :attr:`~plan_bridge.skills.registry.Skill.simulated` skill)
        replaces it: your skill for that action, the rest simulated. One for an action
        that already has a user's skill is an error naming both; ``registered_by`` says
        who registered the other (for messages, e.g. "the domain's setup()"). An entry
        registered there by this same map (a domain's ``setup()`` that returns the same
        registry each time) is left as it is. Nothing is registered unless every entry
        fits.
        """
        problems: list[MapProblem] = []
        owner = registered_by or "the registry"
        new: list[SkillMapEntry] = []
        for entry in self.entries:
            existing = registered_skill(registry, entry.action, entry.variant)
            if existing is None or existing.simulated:
                new.append(entry)
                continue
            if existing.factory == entry.factory and existing.outcome_map == entry.outcome_map:
                continue  # this map's entry, applied before
            shown = describe_factory(existing.factory)
            if entry.variant:
                what = f"a variant {entry.variant!r} of the skill for {entry.action!r} ({shown})"
            else:
                what = f"a skill for {entry.action!r} ({shown})"
            problems.append(
                MapProblem(
                    str(entry.path),
                    entry.line,
                    f"{entry.label} maps it to {entry.target}, but {owner} already registered "
                    f"{what}; an action has one skill (and one of each variant): remove the "
                    f"map entry or the other registration, or make this entry another way to "
                    f'perform the action with variant = "NAME"',
                )
            )
        if problems:
            raise SkillMapError(problems)
        for entry in new:
            registry.remove(entry.action, entry.variant)
            registry.register(
                entry.action,
                outcome_map=dict(entry.outcome_map) or None,
                variant=entry.variant or None,
                simulated=False,
            )(entry.factory)
        return registry


def registered_skill(registry: SkillRegistry, action: str, variant: str = "") -> Skill | None:
    """The skill ``registry`` has for ``action`` (or for one of its variants), or None."""
    return registry.get_variant(action, variant) if variant else registry.get(action)


def describe_factory(factory: object) -> str:
    """``module:qualname`` of a factory (with the selected arguments, if any)."""
    if isinstance(factory, SelectedArguments):
        return f"{describe_factory(factory.factory)}({', '.join(factory.shown)})"
    module = getattr(factory, "__module__", None)
    name = factory_name(factory)
    return f"{module}:{name}" if module else name
