"""``ServiceState``: call a ROS 2 service once and map the response to an outcome.

Bounded and preemptable: waiting for the service (``server_wait_timeout`` ->
``aborted``), and waiting for the response (``call_timeout`` -> ``aborted``, or
a resend when ``call_attempts`` > 1; the server leaving the ROS graph -> ``aborted``; a preempt -> the pending request is
abandoned and the state returns ``preempted``: ROS 2 services cannot be cancelled,
so the server may still carry the request out). Every failure of the user's
callbacks or of the request building is ``aborted`` with the reason logged (the
ROS 2 original raised ``NameError`` there).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import smach
from smach.ros.executor import seconds
from smach.ros.ros_state import POLL_PERIOD, RosState
from smach.ros.shared_node import node_optional

__all__ = ["ServiceState"]

DEFAULT_OUTCOMES = ("succeeded", "aborted", "preempted")
_NO_ANSWER = object()  # _await_response: the call_timeout passed without an answer


class ServiceState(RosState):
    """A state that calls a service.

    Signature of the ROS 2 smach_ros (the node first), plus ``server_wait_timeout``,
    ``call_timeout``, ``call_attempts`` and ``liveness_period``. ``call_attempts``
    sends the request again when no answer came within ``call_timeout`` (for
    idempotent services: a request or response sent while DDS is still matching a
    freshly started server can be lost). Callbacks run in the executing thread:
    ``request_cb(ud, request, *args, **kwargs)`` may return a new request;
    ``response_cb(ud, response, *args, **kwargs)`` may return an outcome.
    """

    @node_optional
    def __init__(
        self,
        node: Any,
        service_name: str,
        service_spec: Any,
        request: Any = None,
        request_cb: Callable[..., Any] | None = None,
        request_cb_args: Sequence[Any] | None = None,
        request_cb_kwargs: Mapping[str, Any] | None = None,
        request_key: str | None = None,
        request_slots: Sequence[str] | None = None,
        response_cb: Callable[..., Any] | None = None,
        response_cb_args: Sequence[Any] | None = None,
        response_cb_kwargs: Mapping[str, Any] | None = None,
        response_key: str | None = None,
        response_slots: Sequence[str] | None = None,
        input_keys: Iterable[str] | None = None,
        output_keys: Iterable[str] | None = None,
        outcomes: Iterable[str] | None = None,
        *,
        server_wait_timeout: Any = 60.0,
        call_timeout: Any = None,
        call_attempts: int = 1,
        liveness_period: Any = 0.5,
    ) -> None:
        super().__init__(node, outcomes=[*DEFAULT_OUTCOMES, *(outcomes or ())])
        self._ros_name = self._service_name = service_name
        self._spec = service_spec
        self._server_wait_timeout = seconds(server_wait_timeout, "server_wait_timeout")
        self._call_timeout = seconds(call_timeout, "call_timeout")
        if not isinstance(call_attempts, int) or call_attempts < 1:
            raise smach.InvalidStateError(
                f"ServiceState {service_name!r}: call_attempts must be an integer >= 1, "
                f"got {call_attempts!r}"
            )
        if call_attempts > 1 and self._call_timeout is None:
            raise smach.InvalidStateError(
                f"ServiceState {service_name!r}: call_attempts > 1 needs a call_timeout"
            )
        self._call_attempts = call_attempts
        self._liveness_period = seconds(liveness_period, "liveness_period")
        self._request = service_spec.Request() if request is None else request
        self._request_key = request_key
        self._request_slots = list(request_slots or ())
        self._response_key = response_key
        self._response_slots = list(response_slots or ())
        for what, slots, message in (
            ("request_slots", self._request_slots, service_spec.Request),
            ("response_slots", self._response_slots, service_spec.Response),
        ):
            fields = message.get_fields_and_field_types()
            unknown = [slot for slot in slots if slot not in fields]
            if unknown:
                raise smach.InvalidStateError(
                    f"ServiceState {service_name!r}: {what} {unknown} are not fields of "
                    f"{message.__name__}; fields: {', '.join(fields) or 'none'}"
                )
        self._request_cb = self._callback(
            "request_cb", request_cb, request_cb_args, request_cb_kwargs
        )
        self._response_cb = self._callback(
            "response_cb", response_cb, response_cb_args, response_cb_kwargs
        )
        self.register_input_keys([*(input_keys or ()), *self._request_slots])
        self.register_output_keys([*(output_keys or ()), *self._response_slots])
        if request_key is not None:
            self.register_input_keys([request_key])
        if response_key is not None:
            self.register_output_keys([response_key])

        helper = self._helper()
        self._resolved_name: str = node.resolve_service_name(service_name)
        self._client: Any = helper.node.create_client(
            service_spec, self._resolved_name, callback_group=helper.callback_group
        )
        self._helper_node: Any = helper.node

    def _ready(self) -> bool:
        return bool(self._client.service_is_ready())

    def execute(self, ud: smach.UserData) -> str:
        if self.preempt_requested():
            return self._preempted()
        waited = self._wait_until(self._ready, self._server_wait_timeout)
        if waited == "preempted":
            return self._preempted()
        if waited == "timeout":
            return self._fail(
                f"service {self._resolved_name!r} did not appear within "
                f"{self._server_wait_timeout} s (server_wait_timeout)"
            )

        request = self._request
        if self._request_key is not None:
            if self._request_key not in ud:
                return self._fail(f"request key {self._request_key!r} is not in the userdata")
            request = ud[self._request_key]
        for slot in self._request_slots:
            if slot not in ud:
                return self._fail(f"request slot {slot!r} is not in the userdata")
            try:
                setattr(request, slot, ud[slot])
            except (AttributeError, TypeError, ValueError, AssertionError) as exc:
                return self._fail(f"request slot {slot!r}: {type(exc).__name__}: {exc}")
        if self._request_cb is not None:
            cb, args, kwargs = self._request_cb
            try:
                new_request = cb(ud, request, *args, **kwargs)
            except Exception as exc:
                return self._fail(f"request_cb raised {type(exc).__name__}: {exc}")
            if new_request is not None:
                request = new_request
        if not isinstance(request, self._spec.Request):
            return self._fail(
                f"the request is a {type(request).__name__}, not a {self._spec.Request.__name__}"
            )

        response: Any = _NO_ANSWER
        for attempt in range(1, self._call_attempts + 1):
            self._wake.clear()
            try:
                future = self._client.call_async(request)
            except Exception as exc:
                return self._fail(
                    f"calling {self._resolved_name!r} failed: {type(exc).__name__}: {exc}"
                )
            future.add_done_callback(lambda _: self._wake.set())
            response = self._await_response(future)
            if response is not _NO_ANSWER:
                break
            if attempt < self._call_attempts:
                smach.logwarn(
                    f"{self.path or 'ServiceState'}: service {self._resolved_name!r} did not "
                    f"answer within {self._call_timeout} s; sending the request again "
                    f"(attempt {attempt + 1} of {self._call_attempts})"
                )
        if response is _NO_ANSWER:
            return self._fail(
                f"service {self._resolved_name!r} did not answer within "
                f"{self._call_timeout} s (call_timeout)"
                + (f", {self._call_attempts} attempts" if self._call_attempts > 1 else "")
            )
        if isinstance(response, str):
            return response

        outcome = "succeeded"
        if self._response_cb is not None:
            cb, args, kwargs = self._response_cb
            try:
                cb_outcome = cb(ud, response, *args, **kwargs)
            except Exception as exc:
                return self._fail(f"response_cb raised {type(exc).__name__}: {exc}")
            if cb_outcome is not None:
                if cb_outcome not in self.get_registered_outcomes():
                    return self._fail(
                        f"response_cb returned {cb_outcome!r}; registered outcomes: "
                        f"{', '.join(self.get_registered_outcomes())}"
                    )
                outcome = cb_outcome
        if self._response_key is not None:
            ud[self._response_key] = response
        for slot in self._response_slots:
            ud[slot] = getattr(response, slot)
        if outcome == "preempted":
            self.service_preempt()
        return str(outcome)

    def _await_response(self, future: Any) -> Any:
        """The response, the outcome to return instead (a string), or ``_NO_ANSWER``."""
        start = time.monotonic()
        deadline = None if self._call_timeout is None else start + self._call_timeout
        period = self._liveness_period
        next_check = None if period is None else start + period
        lost = 0
        while not future.done():
            if self.preempt_requested():
                self._client.remove_pending_request(future)
                return self._preempted()
            now = time.monotonic()
            if deadline is not None and now >= deadline:
                self._client.remove_pending_request(future)
                return _NO_ANSWER
            if next_check is not None and now >= next_check:
                next_check = now + (period or POLL_PERIOD)
                lost = 0 if self._ready() else lost + 1
                if lost >= 2:
                    self._client.remove_pending_request(future)
                    return self._fail(
                        f"service {self._resolved_name!r} disappeared before answering"
                    )
            limits = [t for t in (deadline, next_check) if t is not None]
            self._wait(None if not limits else min(limits) - time.monotonic())
        try:
            return future.result()
        except Exception as exc:
            return self._fail(
                f"service {self._resolved_name!r} failed: {type(exc).__name__}: {exc}"
            )

    def destroy(self) -> None:
        """Release the service client (the state cannot execute afterwards)."""
        self._helper_node.destroy_client(self._client)
