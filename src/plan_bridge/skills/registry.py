"""Skills: the hand-written SMACH behaviour behind each PDDL action.

A skill registry maps action names to factories. A factory takes the action's
arguments (object names, in PDDL parameter order) and returns a ``smach.State``,
typically a StateMachine. The state must have the outcomes ``succeeded``,
``aborted`` and ``preempted``; other outcomes are allowed when mapped to one of those
with ``outcome_map``. A skill can read the keys ``action``, ``arguments`` and
``params`` (parameter name -> object) and may write ``observations``, a mapping
{fact: True/False} or a list of (fact, bool) pairs, to report what it saw::

    skills = SkillRegistry()

    @skills.register("pick")
    def pick(obj: str, place: str) -> smach.State:
        sm = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
        ...
        return sm
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import smach
from plan_bridge.errors import PlanBridgeError

if TYPE_CHECKING:
    from plan_bridge.execution.world import World
    from plan_bridge.pddl.task import PlanningTask
    from plan_bridge.planning.types import PlanStep

__all__ = ["REQUIRED_OUTCOMES", "STEP_KEYS", "Skill", "SkillError", "SkillRegistry"]

REQUIRED_OUTCOMES = ("succeeded", "aborted", "preempted")
#: Keys the executive provides to every skill.
STEP_KEYS = ("action", "arguments", "params")
#: The key a skill writes to report observations.
OBSERVATIONS_KEY = "observations"

SkillFactory = Callable[..., smach.State]


class SkillError(PlanBridgeError):
    """A skill is missing, has the wrong arity, or has unmapped outcomes."""


@dataclass(frozen=True)
class Skill:
    """A registered factory and how its outcomes map to the executive's three."""

    action: str
    factory: SkillFactory
    outcome_map: Mapping[str, str] = field(default_factory=dict)
    variant: str = ""
    """The variant's name; ``""`` for the action's main skill."""
    simulated: bool = False
    """Whether the skill acts on the simulated world itself (a domain's simulated skill).

    False for a user's own skill (a robot driver, a skill-map entry): when it succeeds,
    a simulated world takes the action's declared effects into its truth
    (:meth:`~plan_bridge.execution.world.World.adopt`), so the simulated skills around
    it see what it did. See "The skill contract" in docs/plan-bridge.md."""

    def map_outcome(self, outcome: str) -> str:
        return self.outcome_map.get(outcome, outcome)

    def arity_problem(self, arity: int) -> str | None:
        """Why the factory cannot take ``arity`` positional arguments, or None."""
        try:
            signature = inspect.signature(self.factory)
        except (TypeError, ValueError):
            return None
        try:
            signature.bind(*(["x"] * arity))
        except TypeError as exc:
            return f"its factory {self.factory.__qualname__}{signature} cannot take {arity} argument(s): {exc}"
        return None

    def outcome_problems(self, state: smach.State) -> list[str]:
        outcomes = state.get_registered_outcomes()
        problems = []
        for required in REQUIRED_OUTCOMES:
            if required == "preempted":
                continue  # optional: see outcome_warnings
            if required not in outcomes and required not in self.outcome_map.values():
                problems.append(f"it has no outcome {required!r} (outcomes: {', '.join(outcomes)})")
        for outcome in outcomes:
            mapped = self.map_outcome(outcome)
            if mapped not in REQUIRED_OUTCOMES:
                problems.append(
                    f"its outcome {outcome!r} is not one of {', '.join(REQUIRED_OUTCOMES)}; "
                    f"map it with outcome_map={{{outcome!r}: 'aborted'}} (or another of them)"
                )
        for source, target in self.outcome_map.items():
            if source not in outcomes:
                problems.append(f"outcome_map names {source!r}, which is not an outcome of it")
            if target not in REQUIRED_OUTCOMES:
                problems.append(
                    f"outcome_map sends {source!r} to {target!r}, not to one of {REQUIRED_OUTCOMES}"
                )
        return problems

    def outcome_warnings(self, state: smach.State) -> list[str]:
        """What is allowed but worth knowing about ``state``'s outcomes: a skill without
        ``preempted`` (as many SMACH tutorial states are) is not stopped by a preempt;
        the executive lets its step finish, then stops the plan."""
        outcomes = state.get_registered_outcomes()
        if "preempted" in outcomes or "preempted" in self.outcome_map.values():
            return []
        return [
            f"it has no outcome 'preempted' (outcomes: {', '.join(outcomes)}): a preempt "
            f"does not stop it; the executive lets such a step finish before it stops the plan"
        ]


class SkillRegistry:
    """Action name -> :class:`Skill`."""

    def __init__(
        self,
        fallback: Callable[[PlanStep], smach.State] | None = None,
        *,
        simulated: bool = False,
    ) -> None:
        self._skills: dict[str, Skill] = {}
        #: The default of :attr:`Skill.simulated` for skills registered here: True in a
        #: domain's registry of simulated skills, False (a user's own skills) otherwise.
        self.simulated = simulated
        #: Other ways to perform an action (``register(..., variant="two-handed")``), in
        #: registration order: the executive tries them when the main skill keeps failing.
        self._variants: dict[str, dict[str, Skill]] = {}
        #: Builds a state for actions without a registered skill (e.g. symbolic skills).
        #: A fallback is the world's own simulation of the action.
        self.fallback = fallback
        #: The world the fallback (and the simulated skills) act on; set by
        #: :func:`~plan_bridge.execution.simulation.symbolic_skills` and friends, so that
        #: ``Executive(task, skills)`` finds it without being told.
        self.world: World | None = None

    def register(
        self,
        action: str,
        *,
        outcome_map: Mapping[str, str] | None = None,
        variant: str | None = None,
        simulated: bool | None = None,
    ) -> Callable[[SkillFactory], SkillFactory]:
        """Decorator: ``@skills.register("pick")`` on a factory ``f(*args) -> State``.

        ``variant="..."`` registers another way to perform the action (a different
        grasp, a slower approach); the executive switches to it when the main skill
        fails while the plan is still valid. ``simulated`` (default: the registry's
        :attr:`simulated`) says whether the skill acts on the simulated world itself
        (see :attr:`Skill.simulated`)."""
        name = action.lower()
        sim = self.simulated if simulated is None else simulated

        def decorate(factory: SkillFactory) -> SkillFactory:
            if variant:
                known = self._variants.setdefault(name, {})
                if variant in known:
                    raise SkillError(
                        f"a variant {variant!r} of the skill for {name!r} is already registered"
                    )
                if not callable(factory):
                    raise SkillError(
                        f"the skill variant {name!r}/{variant!r} must be callable, got {factory!r}"
                    )
                known[variant] = Skill(name, factory, dict(outcome_map or {}), variant, sim)
                return factory
            if name in self._skills:
                raise SkillError(
                    f"a skill for action {name!r} is already registered "
                    f"({self._skills[name].factory.__qualname__})"
                )
            if not callable(factory):
                raise SkillError(f"the skill for {name!r} must be callable, got {factory!r}")
            self._skills[name] = Skill(name, factory, dict(outcome_map or {}), simulated=sim)
            return factory

        return decorate

    def add(
        self,
        action: str,
        factory: SkillFactory,
        *,
        outcome_map: Mapping[str, str] | None = None,
        simulated: bool | None = None,
    ) -> None:
        """Register without a decorator."""
        self.register(action, outcome_map=outcome_map, simulated=simulated)(factory)

    def __contains__(self, action: object) -> bool:
        return isinstance(action, str) and action.lower() in self._skills

    def get(self, action: str) -> Skill | None:
        return self._skills.get(action.lower())

    def remove(self, action: str, variant: str = "") -> Skill | None:
        """Unregister the skill for ``action`` (or its ``variant``); the removed one."""
        if variant:
            return self._variants.get(action.lower(), {}).pop(variant, None)
        return self._skills.pop(action.lower(), None)

    def get_variant(self, action: str, variant: str) -> Skill | None:
        """The skill registered as ``variant`` of ``action``, or None."""
        return self._variants.get(action.lower(), {}).get(variant)

    def variants(self, action: str) -> tuple[str, ...]:
        """Names of the variants registered for ``action``, in registration order."""
        return tuple(self._variants.get(action.lower(), ()))

    @property
    def actions(self) -> list[str]:
        return sorted(self._skills)

    def create(
        self, step: PlanStep, variant: str | None = None
    ) -> tuple[smach.State, Skill | None]:
        """Build the state for one plan step (and the skill it came from, if any);
        ``variant`` picks one of the action's :meth:`variants`."""
        if variant:
            skill = self._variants.get(step.action, {}).get(variant)
            if skill is None:
                raise SkillError(
                    f"no variant {variant!r} of the skill for {step.action!r}; variants: "
                    f"{', '.join(self.variants(step.action)) or 'none'}"
                )
        else:
            skill = self._skills.get(step.action)
        if skill is None:
            if self.fallback is None:
                raise SkillError(
                    f"no skill for action {step.action!r} (step {step}); registered skills: "
                    f"{', '.join(self.actions) or 'none'}"
                )
            return self.fallback(step), None
        try:
            state = skill.factory(*step.arguments)
        except Exception as exc:
            raise SkillError(
                f"the skill factory for {step} ({skill.factory.__qualname__}) raised "
                f"{type(exc).__name__}: {exc}"
            ) from exc
        if not isinstance(state, smach.State):
            raise SkillError(
                f"the skill factory for {step} returned {type(state).__name__}, not a smach.State"
            )
        return state, skill

    def check(self, task: PlanningTask, warnings: list[str] | None = None) -> list[str]:
        """Every problem binding this registry to ``task``'s actions, one line each.

        Each skill is built once with example arguments (objects of the right types)
        to check its outcomes, so factories should only construct states. What is
        allowed but worth a warning (a skill without a ``preempted`` outcome) is
        appended to ``warnings``, when given.
        """
        noted: list[str] = [] if warnings is None else warnings
        from plan_bridge.planning.types import PlanStep

        problems: list[str] = []
        for name in sorted(self._skills):
            if name not in task.actions:
                problems.append(
                    f"skill {name!r}: the domain has no action {name!r}; actions: "
                    f"{', '.join(sorted(task.actions))}"
                )
        for name, schema in sorted(task.actions.items()):
            skill = self._skills.get(name)
            if skill is None:
                if self.fallback is None:
                    problems.append(
                        f"action {name!r}: no skill registered (and no fallback such as "
                        f"symbolic skills)"
                    )
                continue
            arity = skill.arity_problem(schema.arity)
            if arity:
                problems.append(f"skill {name!r}: {arity}")
                continue
            example = []
            for parameter in schema.parameters:
                candidates = task.objects_of_type(parameter.type)
                example.append(candidates[0] if candidates else parameter.name)
            try:
                state, _ = self.create(PlanStep(name, tuple(example)))
            except SkillError as exc:
                problems.append(f"skill {name!r}: {exc}")
                continue
            problems.extend(f"skill {name!r}: {p}" for p in skill.outcome_problems(state))
            noted.extend(f"skill {name!r}: {w}" for w in skill.outcome_warnings(state))
            for variant in self.variants(name):
                label = f"skill {name!r} variant {variant!r}"
                try:
                    state, other = self.create(PlanStep(name, tuple(example)), variant)
                except SkillError as exc:
                    problems.append(f"{label}: {exc}")
                    continue
                assert other is not None
                problems.extend(f"{label}: {p}" for p in other.outcome_problems(state))
                noted.extend(f"{label}: {w}" for w in other.outcome_warnings(state))
        for name in sorted(set(self._variants) - set(task.actions)):
            problems.append(
                f"skill variants of {name!r}: the domain has no action {name!r}; actions: "
                f"{', '.join(sorted(task.actions))}"
            )
        return problems
