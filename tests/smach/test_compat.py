"""Compatibility with the original SMACH: names, signatures, porting idioms."""

from __future__ import annotations

import importlib
import inspect
import subprocess
import sys
import threading

import pytest
from smach_helpers import HANG, Blocker, Fn, Leaf, LogRecorder

import smach

# -- names ---------------------------------------------------------------------------------------

KEPT_NAMES = [
    "State",
    "CBState",
    "cb_interface",
    "CBInterface",
    "has_smach_interface",
    "UserData",
    "Remapper",
    "Container",
    "StateMachine",
    "Sequence",
    "Concurrence",
    "Iterator",
    "set_loggers",
    "loginfo",
    "logwarn",
    "logerr",
    "logdebug",
    "set_shutdown_check",
    "is_shutdown",
    "InvalidStateError",
    "InvalidTransitionError",
    "InvalidUserCodeError",
    "InvalidConstructionError",
]

SUBMODULES = [
    "state",
    "state_machine",
    "user_data",
    "container",
    "concurrence",
    "sequence",
    "iterator",
    "exceptions",
    "util",
    "log",
]


@pytest.mark.parametrize("name", KEPT_NAMES)
def test_public_name_exists(name: str) -> None:
    assert hasattr(smach, name)


@pytest.mark.parametrize("name", SUBMODULES)
def test_submodule_is_importable_and_an_attribute(name: str) -> None:
    module = importlib.import_module(f"smach.{name}")
    assert getattr(smach, name) is module


def test_submodules_expose_the_classes_users_import() -> None:
    assert smach.state.State is smach.State
    assert smach.state.CBState is smach.CBState
    assert smach.container.Container is smach.Container
    assert smach.state_machine.StateMachine is smach.StateMachine
    assert smach.concurrence.Concurrence is smach.Concurrence
    assert smach.sequence.Sequence is smach.Sequence
    assert smach.iterator.Iterator is smach.Iterator
    assert smach.user_data.UserData is smach.UserData
    assert smach.user_data.Remapper is smach.Remapper
    assert callable(smach.user_data.get_const)
    assert smach.user_data.Const is not None
    assert smach.util.cb_interface is smach.cb_interface


@pytest.mark.parametrize(
    "name",
    [
        "InvalidStateError",
        "InvalidTransitionError",
        "InvalidUserCodeError",
        "InvalidConstructionError",
    ],
)
def test_exceptions_subclass_smach_error(name: str) -> None:
    cls = getattr(smach, name)
    assert issubclass(cls, smach.exceptions.SmachError)
    assert issubclass(cls, Exception)
    assert str(cls("message")) == "message"


def test_containers_are_states() -> None:
    for cls in (
        smach.Container,
        smach.StateMachine,
        smach.Sequence,
        smach.Concurrence,
        smach.Iterator,
    ):
        assert issubclass(cls, smach.State)
    assert issubclass(smach.Sequence, smach.StateMachine)


def test_import_smach_does_not_import_planning_or_ros() -> None:
    code = (
        "import sys, smach\n"
        "bad = sorted(m for m in sys.modules if m.split('.')[0] in "
        "('unified_planning', 'rclpy', 'plan_bridge', 'rospy'))\n"
        "print(','.join(bad))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True
    )
    assert result.stdout.strip() == ""


# -- signatures ----------------------------------------------------------------------------------


def params(fn: object) -> list[tuple[str, object]]:
    sig = inspect.signature(fn)  # type: ignore[arg-type]
    return [(p.name, p.default) for p in sig.parameters.values() if p.name != "self"]


def names(fn: object) -> list[str]:
    return [name for name, _ in params(fn)]


def test_state_signature() -> None:
    assert names(smach.State.__init__) == ["outcomes", "input_keys", "output_keys", "io_keys"]
    state = smach.State()
    assert state.get_registered_outcomes() == ()


def test_cbstate_signature() -> None:
    assert names(smach.CBState.__init__) == [
        "cb",
        "cb_args",
        "cb_kwargs",
        "outcomes",
        "input_keys",
        "output_keys",
        "io_keys",
    ]


def test_container_signature() -> None:
    assert names(smach.Container.__init__) == ["outcomes", "input_keys", "output_keys"]


def test_statemachine_signatures() -> None:
    assert names(smach.StateMachine.__init__) == ["outcomes", "input_keys", "output_keys"]
    sm = smach.StateMachine(["done"])
    assert names(sm.add) == ["label", "state", "transitions", "remapping", "constants"]
    assert [d for _, d in params(sm.add)][2:] == [None, None, None]
    assert names(sm.add_auto) == [
        "label",
        "state",
        "connector_outcomes",
        "transitions",
        "remapping",
        "constants",
    ]


def test_sequence_signature() -> None:
    assert names(smach.Sequence.__init__) == [
        "outcomes",
        "connector_outcome",
        "input_keys",
        "output_keys",
    ]


def test_concurrence_signature() -> None:
    assert names(smach.Concurrence.__init__) == [
        "outcomes",
        "default_outcome",
        "input_keys",
        "output_keys",
        "outcome_map",
        "outcome_cb",
        "child_termination_cb",
    ]
    cc = smach.Concurrence(["done"], "done")
    assert names(cc.add)[:3] == ["label", "state", "remapping"]


def test_iterator_signature() -> None:
    p = params(smach.Iterator.__init__)
    assert [n for n, _ in p] == [
        "outcomes",
        "input_keys",
        "output_keys",
        "it",
        "it_label",
        "exhausted_outcome",
    ]
    defaults = dict(p)
    assert defaults["it_label"] == "it_data"
    assert defaults["exhausted_outcome"] == "exhausted"
    assert defaults["input_keys"] is inspect.Parameter.empty
    assert defaults["output_keys"] is inspect.Parameter.empty
    it = smach.Iterator(["done"], [], [])
    assert names(it.set_iteritems) == ["it", "it_label"]
    assert names(it.set_contained_state)[:5] == [
        "label",
        "state",
        "loop_outcomes",
        "break_outcomes",
        "final_outcome_map",
    ]


def test_userdata_and_remapper_signatures() -> None:
    assert names(smach.Remapper.__init__)[:4] == ["ud", "input_keys", "output_keys", "remapping"]
    smach.Remapper(smach.UserData(), [], [], {})
    smach.Remapper(smach.UserData(), ["a"], ["b"], {"a": "x"})


def test_cb_interface_signature() -> None:
    assert names(smach.cb_interface)[:3] == ["outcomes", "input_keys", "output_keys"]
    assert "io_keys" in names(smach.cb_interface)


def test_register_callback_signatures() -> None:
    sm = smach.StateMachine(["done"])
    assert names(sm.register_start_cb) == ["start_cb", "cb_args"]
    assert names(sm.register_transition_cb) == ["transition_cb", "cb_args"]
    assert names(sm.register_termination_cb) == ["termination_cb", "cb_args"]


def test_set_loggers_argument_order() -> None:
    assert names(smach.set_loggers) == ["info", "warn", "debug", "error"]


# -- porting idioms ------------------------------------------------------------------------------


class Foo(smach.State):
    """The state of the SMACH tutorial."""

    def __init__(self) -> None:
        smach.State.__init__(
            self,
            outcomes=["outcome1", "outcome2"],
            input_keys=["foo_counter_in"],
            output_keys=["foo_counter_out"],
        )

    def execute(self, userdata):  # type: ignore[no-untyped-def]
        if userdata.foo_counter_in < 3:
            userdata.foo_counter_out = userdata.foo_counter_in + 1
            return "outcome1"
        return "outcome2"


class Bar(smach.State):
    def __init__(self) -> None:
        smach.State.__init__(self, outcomes=["outcome1"], input_keys=["bar_counter_in"])

    def execute(self, userdata):  # type: ignore[no-untyped-def]
        return "outcome1"


def test_tutorial_state_machine_with_userdata_runs_unchanged() -> None:
    sm = smach.StateMachine(outcomes=["outcome4"])
    sm.userdata.sm_counter = 0
    with sm:
        smach.StateMachine.add(
            "FOO",
            Foo(),
            transitions={"outcome1": "BAR", "outcome2": "outcome4"},
            remapping={"foo_counter_in": "sm_counter", "foo_counter_out": "sm_counter"},
        )
        smach.StateMachine.add(
            "BAR",
            Bar(),
            transitions={"outcome1": "FOO"},
            remapping={"bar_counter_in": "sm_counter"},
        )
    assert sm.execute() == "outcome4"
    assert sm.userdata.sm_counter == 3


def test_instance_add_idiom() -> None:
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        sm.add("A", Leaf(["next"]), transitions={"next": "B"})
        sm.add("B", Leaf())
    assert sm.execute() == "done"


def test_cbstate_with_cb_interface_decorator() -> None:
    @smach.cb_interface(input_keys=["x"], output_keys=["y"], outcomes=["ok", "ko"])
    def double(ud):  # type: ignore[no-untyped-def]
        ud.y = ud.x * 2
        return "ok"

    assert smach.has_smach_interface(double)
    assert isinstance(double, smach.CBInterface)
    sm = smach.StateMachine(["ok", "ko"])
    sm.userdata.x = 4
    with sm:
        smach.StateMachine.add("DOUBLE", smach.CBState(double))
    assert sm.execute() == "ok"
    assert sm.userdata.y == 8


def test_cb_interface_io_keys_are_registered() -> None:
    @smach.cb_interface(outcomes=["ok"], io_keys=["counter"])
    def increment(ud):  # type: ignore[no-untyped-def]
        ud.counter += 1
        return "ok"

    assert increment.get_registered_input_keys() == ("counter",)
    assert increment.get_registered_output_keys() == ("counter",)
    sm = smach.StateMachine(["ok"])
    sm.userdata.counter = 1
    sm.add("INC", smach.CBState(increment))
    sm.execute()
    assert sm.userdata.counter == 2


def test_cbinterface_constructor_with_io_keys() -> None:
    iface = smach.CBInterface(lambda ud: "ok", outcomes=["ok"], io_keys=["k"])
    assert iface.get_registered_input_keys() == ("k",)
    assert iface.get_registered_output_keys() == ("k",)
    assert iface.get_registered_outcomes() == ("ok",)
    assert iface(None) == "ok"


def test_cb_interface_on_methods_binds_self() -> None:
    class Robot:
        def __init__(self) -> None:
            self.moves = 0

        @smach.cb_interface(outcomes=["moved"], output_keys=["moves"])
        def move(self, ud):  # type: ignore[no-untyped-def]
            self.moves += 1
            ud.moves = self.moves
            return "moved"

    robot = Robot()
    assert smach.has_smach_interface(robot.move)
    state = smach.CBState(robot.move)
    assert state.get_registered_outcomes() == ("moved",)
    sm = smach.StateMachine(["moved"])
    sm.add("MOVE", state)
    assert sm.execute() == "moved"
    assert robot.moves == 1
    assert sm.userdata.moves == 1
    # The explicit-instance style of the original still works too.
    assert Robot.move(robot, smach.Remapper(smach.UserData(), [], ["moves"])) == "moved"


def test_cb_interface_keeps_function_metadata() -> None:
    @smach.cb_interface(outcomes=["ok"])
    def documented(ud):  # type: ignore[no-untyped-def]
        """Docstring."""
        return "ok"

    assert documented.__name__ == "documented"
    assert documented.__doc__ == "Docstring."


def test_has_smach_interface() -> None:
    assert smach.has_smach_interface(smach.State())
    assert not smach.has_smach_interface(lambda ud: "x")


def test_set_loggers_takes_effect_everywhere(logs: LogRecorder) -> None:
    assert smach.loginfo == logs.info.append
    assert smach.logwarn == logs.warn.append
    assert smach.logdebug == logs.debug.append
    assert smach.logerr == logs.error.append
    sm = smach.StateMachine(["done"], input_keys=["missing"])
    sm.add("A", Leaf(["next"]), {"next": "B"})
    sm.add("B", Leaf())
    sm.execute(smach.UserData())  # warns about the missing input key
    joined = "\n".join(logs.info)
    assert "State machine starting in initial state 'A'" in joined
    assert "State machine transitioning 'A':'next'-->'B'" in joined
    assert "State machine terminating 'B':'done'" in joined
    assert any("missing" in m for m in logs.warn)
    smach.logdebug("debug line")
    assert logs.debug == ["debug line"]
    assert logs.error == []


def test_plain_assignment_of_a_logger_takes_effect() -> None:
    lines: list[str] = []
    smach.loginfo = lines.append
    sm = smach.StateMachine(["done"])
    sm.add("A", Leaf())
    sm.execute()
    assert any("starting" in line for line in lines)


def test_concurrence_logs_use_original_strings(logs: LogRecorder) -> None:
    cc = smach.Concurrence(["done"], "done")
    cc.add("A", Leaf(["ok"]))
    cc.execute()
    joined = "\n".join(logs.info)
    assert "Concurrence starting with userdata" in joined
    assert "Concurrent state 'A' returned outcome 'ok' on termination." in joined
    assert "Concurrent Outcomes: {'A': 'ok'}" in joined


def test_default_loggers_go_to_python_logging(caplog: pytest.LogCaptureFixture) -> None:
    smach.log.restore_default_loggers()
    with caplog.at_level("INFO", logger="smach"):
        sm = smach.StateMachine(["done"])
        sm.add("A", Leaf())
        sm.execute()
    assert any("State machine starting" in r.getMessage() for r in caplog.records)
    assert all(r.name == "smach" for r in caplog.records)


def test_set_shutdown_check_replaces_is_shutdown() -> None:
    def down() -> bool:
        return True

    assert smach.is_shutdown() is False
    smach.set_shutdown_check(down)
    assert smach.is_shutdown is down
    sm = smach.StateMachine(["done"])
    sm.add("A", Leaf())
    assert sm.execute() is None


def test_with_block_returns_container_for_as_clause() -> None:
    with smach.StateMachine(["done"]) as sm:
        smach.StateMachine.add("A", Leaf())
    assert isinstance(sm, smach.StateMachine)
    assert sm.execute() == "done"


def test_register_callback_argument_orders() -> None:
    sm = smach.StateMachine(["done"])
    sm.add("A", Leaf(["next"]), {"next": "B"})
    sm.add("B", Leaf())
    got: dict[str, tuple[object, ...]] = {}
    sm.register_start_cb(lambda *a: got.setdefault("start", a), ["x"])
    sm.register_transition_cb(lambda *a: got.setdefault("transition", a), ["y"])
    sm.register_termination_cb(lambda *a: got.setdefault("termination", a), ["z"])
    sm.execute()
    assert got["start"][0] is sm.userdata
    assert got["start"][1:] == (["A"], "x")
    assert got["transition"][0] is sm.userdata
    assert got["transition"][2:] == ("y",)
    assert got["termination"][0] is sm.userdata
    assert got["termination"][1:] == (["B"], "done", "z")


def test_get_active_states_is_empty_when_idle() -> None:
    sm = smach.StateMachine(["done"])
    sm.add("A", Leaf())
    cc = smach.Concurrence(["done"], "done")
    cc.add("A", Leaf())
    it = smach.Iterator(["done"], [], [], it=[], exhausted_outcome="done")
    it.set_contained_state("A", Leaf(["c"]), loop_outcomes=["c"])
    for container in (sm, cc, it):
        assert container.get_active_states() == []
        container.execute()
        assert container.get_active_states() == []


# -- Concurrence outcome policy ----------------------------------------------------------------------


def test_outcome_cb_beats_outcome_map_beats_default() -> None:
    def make(**kwargs: object) -> smach.Concurrence:
        cc = smach.Concurrence(["by_default", "by_map", "by_cb"], "by_default", **kwargs)
        cc.add("A", Leaf(["x"]))
        return cc

    outcome_map = {"by_map": {"A": "x"}}
    assert make().execute() == "by_default"
    assert make(outcome_map=outcome_map).execute() == "by_map"
    assert make(outcome_map=outcome_map, outcome_cb=lambda o: "by_cb").execute() == "by_cb"


def test_outcome_map_entry_with_most_conditions_wins() -> None:
    cc = smach.Concurrence(
        ["one", "two", "default"],
        "default",
        outcome_map={"one": {"A": "x"}, "two": {"A": "x", "B": "y"}},
    )
    cc.add("A", Leaf(["x"]))
    cc.add("B", Leaf(["y"]))
    assert cc.execute() == "two"


def test_outcome_map_tie_goes_to_the_first_entry() -> None:
    cc = smach.Concurrence(
        ["first", "second", "default"],
        "default",
        outcome_map={"first": {"A": "x"}, "second": {"B": "y"}},
    )
    cc.add("A", Leaf(["x"]))
    cc.add("B", Leaf(["y"]))
    assert cc.execute() == "first"


def test_outcome_map_accepts_several_acceptable_outcomes_per_child() -> None:
    def make(result: str) -> smach.Concurrence:
        cc = smach.Concurrence(
            ["failed", "done"], "done", outcome_map={"failed": {"A": ["aborted", "lost"]}}
        )
        cc.add("A", Leaf(["ok", "aborted", "lost"], result=result))
        return cc

    assert make("aborted").execute() == "failed"
    assert make("lost").execute() == "failed"
    assert make("ok").execute() == "done"


def test_outcome_map_is_not_mutated() -> None:
    outcome_map = {"failed": {"A": ["x", "y"]}}
    smach.Concurrence(["failed", "done"], "done", outcome_map=outcome_map)
    assert outcome_map == {"failed": {"A": ["x", "y"]}}


def test_outcome_cb_gets_a_copy_of_the_outcomes() -> None:
    def cb(outcomes: dict[str, str | None]) -> str:
        outcomes["A"] = "tampered"
        return "done"

    cc = smach.Concurrence(["done"], "done", outcome_cb=cb)
    cc.add("A", Leaf(["x"]))
    cc.execute()
    assert cc._child_outcomes == {"A": "x"}


@pytest.mark.timeout(10)
def test_child_termination_cb_true_preempts_all_running_children() -> None:
    b, c = Blocker(), Blocker()
    cc = smach.Concurrence(["done"], "done", child_termination_cb=lambda o: o["A"] is not None)
    release = threading.Event()

    def a_body(s: Fn, ud: object) -> str:
        b.started.wait(HANG)
        c.started.wait(HANG)
        release.set()
        return "done"

    cc.add("A", Fn(a_body))
    cc.add("B", b)
    cc.add("C", c)
    cc.execute()
    assert release.is_set()
    assert b.saw_preempt
    assert c.saw_preempt
    assert cc._child_outcomes == {"A": "done", "B": "preempted", "C": "preempted"}


@pytest.mark.timeout(10)
def test_child_termination_cb_list_preempts_only_listed_children() -> None:
    b = Blocker()
    b_finished = threading.Event()
    c_started = threading.Event()
    c_preempted: list[bool] = []

    def a_body(s: Fn, ud: object) -> str:
        b.started.wait(HANG)
        c_started.wait(HANG)
        return "done"

    class NotifyingBlocker(Blocker):
        def execute(self, ud: object) -> str:
            try:
                return super().execute(ud)
            finally:
                b_finished.set()

    b = NotifyingBlocker()

    def c_body(s: Fn, ud: object) -> str:
        c_started.set()
        b_finished.wait(HANG)
        c_preempted.append(s.preempt_requested())
        return "preempted" if s.preempt_requested() else "done"

    def cb(outcomes: dict[str, str | None]) -> list[str] | bool:
        return ["B"] if outcomes["A"] is not None else False

    cc = smach.Concurrence(["done"], "done", child_termination_cb=cb)
    cc.add("A", Fn(a_body))
    cc.add("B", b)
    cc.add("C", Fn(c_body, ["done", "preempted"]))
    cc.execute()
    assert b.saw_preempt
    assert c_preempted == [False]
    assert cc._child_outcomes == {"A": "done", "B": "preempted", "C": "done"}


@pytest.mark.timeout(10)
def test_concurrence_returns_preempted_only_if_registered() -> None:
    def run(outcomes: list[str]) -> str | None:
        blocker = Blocker()
        cc = smach.Concurrence(outcomes, "done")
        cc.add("B", blocker)
        cc.request_preempt()
        return cc.execute()

    assert run(["done", "preempted"]) == "preempted"
    assert run(["done"]) == "done"


def test_concurrence_set_initial_state_does_not_raise_type_error() -> None:
    cc = smach.Concurrence(["done"], "done")
    cc.add("A", Leaf())
    cc.set_initial_state(["A"], smach.UserData())
    assert cc.get_initial_states() == ["A"]
