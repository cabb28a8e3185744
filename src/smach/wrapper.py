"""``Wrapper``: the base of containers that hold exactly one child.

Retry and Timeout are built on it, and so can user containers that add behaviour
around one state (logging, resource locks, recovery). A subclass implements
:meth:`Wrapper.run`, which runs the child through :meth:`Wrapper.run_child` any number
of times and returns the container's outcome; the base class does construction,
interface inference, userdata scoping, events, preemption forwarding and
introspection.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any, TypeVar

from smach.container import Container, construction_method
from smach.exceptions import InvalidStateError
from smach.state import State
from smach.user_data import Remapper, UserData

__all__ = ["Wrapper"]

W = TypeVar("W", bound="Wrapper")


class Wrapper(Container):
    """A container around one child.

    With ``outcomes=None`` the container's outcomes are the child's plus
    :attr:`extra_outcomes`; with no keys given, its keys are the child's (through the
    remapping), so wrapping a state changes nothing else about the machine.
    """

    #: Outcomes a subclass adds to the inferred ones.
    extra_outcomes: tuple[str, ...] = ("preempted",)

    def __init__(
        self,
        outcomes: Iterable[str] | None = None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
    ) -> None:
        super().__init__(outcomes, input_keys, output_keys)
        # Whether add() takes the outcomes, and the keys, from the child. (One attribute:
        # an instance keeps at most 29, see Container, ``_start_cbs``.)
        self._infer = (outcomes is None, input_keys is None and output_keys is None)
        self._label: str | None = None
        self._child: State | None = None
        self._remapping: dict[str, str] = {}
        self._remapper_cache: Remapper | None = None

    # -- construction ---------------------------------------------------------------------
    @construction_method
    def add(self, label: str, state: State, remapping: Mapping[str, str] | None = None) -> State:
        """Set the wrapped child (one per container)."""
        if self._child is not None:
            raise InvalidStateError(
                f"{self._path}: a {type(self).__name__} holds one child; "
                f"{self._label!r} was already added"
            )
        self.adopt_child(label, state)
        self._label, self._child = label, state
        self._remapping = dict(remapping or {})
        infer_outcomes, infer_keys = self._infer
        if infer_outcomes:
            self.register_outcomes([*state.get_registered_outcomes(), *self.extra_outcomes])
        if infer_keys:
            remap = self._remapping
            self.register_input_keys([remap.get(k, k) for k in state.get_registered_input_keys()])
            self.register_output_keys([remap.get(k, k) for k in state.get_registered_output_keys()])
        self._invalidate()
        return state

    @classmethod
    def wrap(
        cls: type[W],
        label: str,
        state: State,
        remapping: Mapping[str, str] | None = None,
        **options: Any,
    ) -> W:
        """Build the container around ``state`` in one call: ``Retry.wrap('PICK', pick, attempts=3)``."""
        container = cls(**options)
        container.add(label, state, remapping)
        return container

    def consistency_problems(self) -> list[str]:
        """Every reason the container cannot run (a subclass may add its own)."""
        if self._child is None:
            return [
                f"{self._path}: the {type(self).__name__} has no child ({type(self).__name__}.add)"
            ]
        return [
            f"{self._path}/{self._label}: outcome {o!r} is not an outcome of the "
            f"{type(self).__name__}: {', '.join(self._outcomes)}"
            for o in self._child.get_registered_outcomes()
            if o not in self._outcomes
        ]

    # -- execution ---------------------------------------------------------------------------
    def run(self, child: State, label: str) -> str:
        """Run the child (with :meth:`run_child`) and return the container's outcome."""
        raise NotImplementedError

    def run_child(self) -> str:
        """Run the child once: events, exception wrapping and outcome checks included."""
        child, label, remapper = self._child, self._label, self._remapper_cache
        assert child is not None and label is not None and remapper is not None
        return self.step_child(label, child, remapper)

    def compile_children(self) -> None:
        assert self._child is not None and self._label is not None
        self._remapper_cache = self.child_remapper(self._label, self._child, self._remapping)

    def run_children(self) -> str | None:
        child, label = self._child, self._label
        assert child is not None and label is not None
        outcome = self.run(child, label)
        if self._preempt_requested and not child._preempt_requested:
            self.service_preempt()  # the child handled the request on our behalf
        return outcome

    # -- introspection -----------------------------------------------------------------------
    def get_children(self) -> dict[str, State]:
        return {self._label: self._child} if self._child is not None and self._label else {}

    def set_initial_state(
        self, initial_states: Sequence[str], userdata: UserData | None = None
    ) -> None:
        if [s for s in initial_states if s != self._label]:
            raise InvalidStateError(f"{self._path}: the only child is {self._label!r}")
        if userdata is not None:
            self._userdata.update(userdata)

    def get_initial_states(self) -> list[str]:
        return [self._label] if self._label else []

    def get_active_states(self) -> list[str]:
        return [self._label] if self._running and self._label else []

    def get_internal_edges(self) -> list[tuple[str, str, str | None]]:
        if self._child is None or self._label is None:
            return []
        return [(o, self._label, o) for o in self._child.get_registered_outcomes()]
