"""Whole-graph validation of a tree of containers, reported all at once.

Errors are what stops a container from running (the same problems ``close()`` and
``execute()`` raise about). Warnings come from graph analysis with networkx:
unreachable states, states from which no container outcome can be reached, container
outcomes nothing leads to, and input keys that nothing provides. Warnings never block
execution: filling ``sm.userdata`` before ``execute()`` is legitimate, so keys
already present in the userdata count as provided.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    import networkx as nx

    from smach.container import Container
    from smach.state import State
    from smach.state_machine import StateMachine

__all__ = ["Issue", "ValidationReport", "validate"]


@dataclass(frozen=True)
class Issue:
    """One problem: where (a state path), how bad, and what is wrong."""

    severity: Literal["error", "warning"]
    path: str
    message: str

    def __str__(self) -> str:
        return f"{self.severity}: {self.path}: {self.message}"


@dataclass
class ValidationReport:
    """Every issue found in a tree."""

    issues: list[Issue] = field(default_factory=list)

    @property
    def errors(self) -> list[Issue]:
        return [i for i in self.issues if i.severity == "error"]

    @property
    def warnings(self) -> list[Issue]:
        return [i for i in self.issues if i.severity == "warning"]

    @property
    def ok(self) -> bool:
        """True when there are no errors (warnings allowed)."""
        return not self.errors

    def __str__(self) -> str:
        if not self.issues:
            return "no problems found"
        return "\n".join(str(i) for i in self.issues)


def validate(root: Container) -> ValidationReport:
    """Check ``root`` and every container below it."""
    report = ValidationReport()
    _check(root, report)
    return report


def _check(container: Container, report: ValidationReport) -> None:
    from smach.container import Container
    from smach.state_machine import StateMachine

    problems = getattr(container, "consistency_problems", None)
    if problems is not None:
        for line in problems():
            path, _, message = line.partition(": ")
            report.issues.append(Issue("error", path, message))
    else:
        try:
            container.check_consistency()
        except Exception as exc:
            report.issues.append(Issue("error", container.path, str(exc)))
    if isinstance(container, StateMachine):
        _check_graph(container, report)
    else:
        _check_keys_flat(container, report)
    for child in container.get_children().values():
        if isinstance(child, Container):
            _check(child, report)


def _remapped(remapping: dict[str, str], keys: tuple[str, ...]) -> set[str]:
    return {remapping.get(k, k) for k in keys}


def _available(container: Container) -> set[str]:
    return set(container.get_registered_input_keys()) | set(container.userdata.keys())


def _check_graph(sm: Container, report: ValidationReport) -> None:
    # networkx costs 0.1-0.3 s to import: only validation needs it, so import it here.
    import networkx as nx

    from smach.state_machine import StateMachine

    assert isinstance(sm, StateMachine)
    states: dict[str, State] = sm.get_children()
    if not states:
        return
    graph: nx.DiGraph[object] = nx.DiGraph()
    graph.add_nodes_from(states)
    outcome_nodes = {o: ("outcome", o) for o in sm.get_registered_outcomes()}
    graph.add_nodes_from(outcome_nodes.values())
    for label, table in sm._transitions.items():
        for outcome, target in table.items():
            if target in states:
                graph.add_edge(label, target)
            else:
                final = outcome if target in (None, "") else target
                if final in outcome_nodes:
                    graph.add_edge(label, outcome_nodes[final])
    initial = sm._initial_state_label
    if initial not in states:
        return
    reachable = nx.descendants(graph, initial) | {initial}
    _check_reach(sm, graph, initial, reachable, outcome_nodes, report)
    _check_inputs(sm, graph, reachable, report)


def _check_reach(
    sm: StateMachine,
    graph: nx.DiGraph[object],
    initial: str,
    reachable: set[object],
    outcome_nodes: dict[str, tuple[str, str]],
    report: ValidationReport,
) -> None:
    """Unreachable states, states that cannot finish, outcomes never returned."""
    import networkx as nx

    states = sm.get_children()
    for label in states:
        if label not in reachable:
            report.issues.append(
                Issue(
                    "warning", f"{sm.path}/{label}", f"unreachable from initial state {initial!r}"
                )
            )
    can_finish: set[object] = set()
    for node in outcome_nodes.values():
        can_finish |= nx.ancestors(graph, node)
    for label in states:
        if label in reachable and label not in can_finish:
            report.issues.append(
                Issue(
                    "warning",
                    f"{sm.path}/{label}",
                    "no path from this state reaches an outcome of the container "
                    "(the machine can only loop or stop by preemption)",
                )
            )
    for outcome, node in outcome_nodes.items():
        if node not in reachable:
            report.issues.append(
                Issue("warning", sm.path, f"container outcome {outcome!r} is never returned")
            )


def _check_inputs(
    sm: StateMachine, graph: nx.DiGraph[object], reachable: set[object], report: ValidationReport
) -> None:
    """Input keys: provided by the container's inputs, its userdata, constants, or a
    state that can run before the reader."""
    import networkx as nx

    states = sm.get_children()
    available = _available(sm)
    for consts in sm._constants.values():
        available |= set(consts)
    writes = {
        label: _remapped(sm._remappings[label], state.get_registered_output_keys())
        for label, state in states.items()
    }
    for label, state in states.items():
        if label not in reachable:
            continue
        before = nx.ancestors(graph, label) | ({label} if graph.has_edge(label, label) else set())
        provided = set(available)
        for other in before:
            if other in writes:
                provided |= writes[other]
        remap = sm._remappings[label]
        for key in state.get_registered_input_keys():
            target = remap.get(key, key)
            if target not in provided:
                shown = f"{key!r}" + (f" (remapped to {target!r})" if target != key else "")
                report.issues.append(
                    Issue(
                        "warning",
                        f"{sm.path}/{label}",
                        f"input key {shown} is not provided: it is not an input key of "
                        f"{sm.path}, not in its userdata, and no state that can run before "
                        f"this one writes it",
                    )
                )


def _check_keys_flat(container: Container, report: ValidationReport) -> None:
    """For containers without transitions: inputs come from the container or siblings."""
    children = container.get_children()
    remappings: dict[str, dict[str, str]] = getattr(container, "_remappings", {})
    if not remappings and hasattr(container, "_remapping"):
        remappings = dict.fromkeys(children, container._remapping)
    available = _available(container)
    items_label = getattr(container, "_items_label", None)
    if items_label:
        available.add(items_label)
    for label, state in children.items():
        available |= _remapped(remappings.get(label, {}), state.get_registered_output_keys())
    for label, state in children.items():
        remap = remappings.get(label, {})
        for key in state.get_registered_input_keys():
            target = remap.get(key, key)
            if target not in available:
                report.issues.append(
                    Issue(
                        "warning",
                        f"{container.path}/{label}",
                        f"input key {key!r} is not provided by {container.path} "
                        f"(not an input key, not in its userdata, no sibling writes it)",
                    )
                )
