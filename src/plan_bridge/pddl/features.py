"""What plan_bridge can do with each PDDL requirement and construct.

Every requirement flag and every construct the front end meets is classified as

* ``supported``: read by unified-planning and planned by the classical engines
  (Fast Downward, pyperplan for STRIPS);
* ``engine``: read by unified-planning, planned only by the engines named in
  :data:`ENGINES` (durative actions, numeric fluents: TAMER, Kairos, ENHSP), each
  with the PyPI package that provides it and whether it is installed;
* ``unsupported``: contingent, conformant, probabilistic, non-deterministic,
  PDDL+ and HTN constructs, derived predicates...: named as such, never as a typo.

The planner layer (:mod:`plan_bridge.planning`) may import :data:`ENGINES` and
:func:`classify`; nothing here imports it (``pddl`` does not depend on ``planning``)
nor unified-planning (installation is checked with ``importlib.util.find_spec``).
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass
from functools import cache

__all__ = [
    "ADL",
    "ENGINES",
    "IMPLIED",
    "Engine",
    "Support",
    "classify",
    "installed_engines",
    "is_installed",
    "known",
    "requirements_hint",
]


@dataclass(frozen=True)
class Engine:
    """A unified-planning engine: its UP name, PyPI package and import module."""

    name: str
    package: str
    module: str


#: The engines the classification refers to, by UP engine name.
ENGINES = {
    "fast-downward": Engine("fast-downward", "up-fast-downward", "up_fast_downward"),
    "pyperplan": Engine("pyperplan", "up-pyperplan", "up_pyperplan"),
    "tamer": Engine("tamer", "up-tamer", "up_tamer"),
    "kairos": Engine("kairos", "up-kairos", "up_kairos"),
    "enhsp": Engine("enhsp", "up-enhsp", "up_enhsp"),
}

_CLASSICAL = ("fast-downward",)
_TEMPORAL = ("kairos", "tamer")
_NUMERIC = ("kairos", "tamer", "enhsp")


@dataclass(frozen=True)
class Support:
    """How one requirement or construct is handled."""

    name: str
    """The requirement flag (``:durative-actions``) or construct (``oneof``)."""
    what: str
    """Plain words: ``"durative actions"``."""
    status: str
    """``"supported"``, ``"engine"`` or ``"unsupported"``."""
    engines: tuple[str, ...] = ()
    """Engines that plan it (for ``supported`` and ``engine``)."""
    reason: str = ""
    """Why it is unsupported, or what to do instead."""

    @property
    def installed_engines(self) -> tuple[str, ...]:
        return tuple(name for name in self.engines if is_installed(name))

    def describe(self) -> str:
        """One sentence for messages: what it is and how it is (or is not) planned."""
        if self.status == "unsupported":
            return f"{self.name} ({self.what}) is not supported: {self.reason}"
        parts = []
        for name in self.engines:
            engine = ENGINES[name]
            state = "installed" if is_installed(name) else "not installed"
            parts.append(f"{name} (package {engine.package}, {state})")
        through = "; ".join(parts)
        if self.status == "supported":
            return f"{self.name} ({self.what}) is supported"
        return f"{self.name} ({self.what}) is supported through the engines {through}"


def _s(name: str, what: str, engines: tuple[str, ...] = _CLASSICAL) -> Support:
    return Support(name, what, "supported", engines)


def _e(name: str, what: str, engines: tuple[str, ...]) -> Support:
    return Support(name, what, "engine", engines)


def _u(name: str, what: str, reason: str) -> Support:
    return Support(name, what, "unsupported", (), reason)


_CONTINGENT = (
    "contingent and conformant planning (plans that branch on observations or hold "
    "for every possible initial state) have no engine in unified-planning 1.3; "
    "plan_bridge observes the world during execution and replans instead"
)
_PROBABILISTIC = (
    "probabilistic planning (PPDDL) has no engine in unified-planning 1.3; model the "
    "likely outcome deterministically and let the executive replan when it fails"
)
_NONDET = (
    "fully observable non-deterministic planning has no engine in unified-planning 1.3; "
    "model one outcome and let the executive replan on the others"
)
_UP_READER = "the unified-planning 1.3 PDDL reader cannot read it"

_REQUIREMENTS = [
    _s(":strips", "add/delete effects", ("fast-downward", "pyperplan")),
    _s(":typing", "typed objects", ("fast-downward", "pyperplan")),
    _s(":negative-preconditions", "negated preconditions"),
    _s(":disjunctive-preconditions", "or/imply in preconditions"),
    _s(":equality", "the = predicate"),
    _s(":existential-preconditions", "exists in preconditions"),
    _s(":universal-preconditions", "forall in preconditions"),
    _s(":quantified-preconditions", "exists/forall in preconditions"),
    _s(":conditional-effects", "when/forall in effects"),
    _s(":adl", "the ADL subset"),
    _s(":action-costs", "action costs (total-cost)"),
    _e(":numeric-fluents", "numeric fluents", _NUMERIC),
    _e(":fluents", "numeric fluents", _NUMERIC),
    _e(":durative-actions", "durative actions", _TEMPORAL),
    _e(":duration-inequalities", "durations given by inequalities", _TEMPORAL),
    _e(":timed-initial-literals", "timed initial literals", _TEMPORAL),
    _e(":timed-initial-effects", "timed initial effects", _TEMPORAL),
    _u(":derived-predicates", "derived predicates (axioms)", _UP_READER),
    _u(":object-fluents", "object-valued fluents", _UP_READER),
    _u(":preferences", "PDDL3 preferences", "no installed or known engine plans them"),
    _u(":constraints", "PDDL3 trajectory constraints", "no installed or known engine plans them"),
    _u(":contingent", "contingent planning", _CONTINGENT),
    _u(":conformant", "conformant planning", _CONTINGENT),
    _u(":partial-observability", "partial observability", _CONTINGENT),
    _u(":probabilistic-effects", "probabilistic effects (PPDDL)", _PROBABILISTIC),
    _u(":rewards", "rewards (PPDDL)", _PROBABILISTIC),
    _u(":non-deterministic", "non-deterministic effects (FOND)", _NONDET),
    _u(":time", "PDDL+ time", "PDDL+ (processes and events) is not planned by plan_bridge"),
    _u(":continuous-effects", "continuous effects (PDDL+)", "PDDL+ is not planned by plan_bridge"),
    _u(
        ":hierarchy",
        "HTN tasks and methods",
        "plan_bridge plans with classical and temporal engines, not HTN",
    ),
    _u(":method-preconditions", "HTN method preconditions", "plan_bridge does not plan HTN"),
    _u(":multi-agent", "multi-agent planning", "plan_bridge plans for one agent"),
    # PDDL 1.2 flags of the first IPC, read by no engine of unified-planning 1.3.
    _u(":domain-axioms", "PDDL 1.2 domain axioms", _UP_READER),
    _u(":safety-constraints", "PDDL 1.2 safety constraints", _UP_READER),
    _u(":expression-evaluation", "PDDL 1.2 expression evaluation", _UP_READER),
    _u(":open-world", "PDDL 1.2 open-world semantics", _UP_READER),
    _u(":true-negation", "PDDL 1.2 true negation", _UP_READER),
    _u(":ucpop", "PDDL 1.2 :adl with axioms and safety constraints", _UP_READER),
    _u(":subgoal-through-axioms", "PDDL 1.2 subgoals through axioms", _UP_READER),
    _u(":action-expansions", "PDDL 1.2 action expansions", _UP_READER),
    _u(":foreach-expansions", "PDDL 1.2 foreach expansions", _UP_READER),
    _u(":dag-expansions", "PDDL 1.2 expansions as graphs", _UP_READER),
    _u(
        ":goal-utilities",
        "net-benefit goal utilities (PDDL 3.1, IPC 2008)",
        "no installed or known engine plans them",
    ),
]
_CONSTRUCTS = [  # not requirement flags
    _u("either", "a union of types", _UP_READER),
    _u(":derived", "a derived predicate (axiom)", _UP_READER),
    _u(":observe", "a sensing action's observation", _CONTINGENT),
    _u("oneof", "one of several facts holds initially, or a non-deterministic effect", _CONTINGENT),
    _u("unknown", "an initially unknown fact", _CONTINGENT),
    _u("or-init", "a disjunctive initial state", _CONTINGENT),
    _u("probabilistic", "a probabilistic effect", _PROBABILISTIC),
    _u(":process", "a PDDL+ process", "PDDL+ is not planned by plan_bridge"),
    _u(":event", "a PDDL+ event", "PDDL+ is not planned by plan_bridge"),
    _u(":task", "an HTN task", "plan_bridge does not plan HTN"),
    _u(":method", "an HTN method", "plan_bridge does not plan HTN"),
    _u(":htn", "an HTN initial task network", "plan_bridge does not plan HTN"),
    _u("preference", "a PDDL3 preference", "no installed or known engine plans them"),
    _u(
        ":vars",
        "PDDL 1.2 free variables of an action",
        _UP_READER + "; declare them in :parameters instead",
    ),
    _u(
        "total-time",
        "the makespan inside a metric expression",
        "the unified-planning 1.3 PDDL reader reads total-time only as "
        "(:metric minimize (total-time)); write that, or leave the metric out to plan "
        "without it",
    ),
    _u(
        "nested-forall-effect",
        "a forall effect inside another forall effect",
        "the unified-planning 1.3 PDDL reader cannot represent it; one forall over "
        "all the variables does the same",
    ),
    _e(":durative-action", "a durative action", _TEMPORAL),
    _e("numeric", "numeric fluents and comparisons", _NUMERIC),
]

_TABLE = _REQUIREMENTS + _CONSTRUCTS
_BY_NAME = {support.name: support for support in _TABLE}

#: The flags ``:adl`` stands for.
ADL = frozenset(
    [
        ":strips",
        ":typing",
        ":negative-preconditions",
        ":disjunctive-preconditions",
        ":equality",
        ":existential-preconditions",
        ":universal-preconditions",
        ":quantified-preconditions",
        ":conditional-effects",
    ]
)
#: Requirements that imply others (``:adl`` brings ``:negative-preconditions``...).
IMPLIED = {
    ":adl": ADL,
    ":quantified-preconditions": frozenset(
        [":existential-preconditions", ":universal-preconditions"]
    ),
    ":fluents": frozenset([":numeric-fluents", ":object-fluents"]),
    ":timed-initial-effects": frozenset([":timed-initial-literals"]),
}


def classify(name: str) -> Support | None:
    """The classification of a requirement flag or construct, ``None`` if unknown."""
    return _BY_NAME.get(name)


def known() -> tuple[Support, ...]:
    """Every classified requirement and construct (for documentation and tests)."""
    return tuple(_TABLE)


def requirements_hint() -> str:
    """The requirement flags by how they are handled, for messages about requirements."""
    groups = {
        status: [s.name for s in _REQUIREMENTS if s.status == status]
        for status in ("supported", "engine", "unsupported")
    }
    return (
        f"supported requirements: {' '.join(groups['supported'])}; through a temporal or "
        f"numeric engine: {' '.join(groups['engine'])}; known but not supported: "
        f"{' '.join(groups['unsupported'])}"
    )


@cache
def is_installed(engine: str) -> bool:
    """Whether the engine's package can be imported (without importing it)."""
    spec = ENGINES.get(engine)
    if spec is None:
        return False
    try:
        return importlib.util.find_spec(spec.module) is not None
    except (ImportError, ValueError):
        return False


def installed_engines() -> tuple[str, ...]:
    return tuple(name for name in ENGINES if is_installed(name))
