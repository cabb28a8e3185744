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
from smach.ros.ros_state import RosState, StateAbort
from smach.ros.shared_node import node_optional

__all__ = ["ServiceState"]

DEFAULT_OUTCOMES = ("succeeded", "aborted", "preempted")
_NO_ANSWER = object()  # _await_response: the call_timeout passed without an answer


class ServiceState(RosState):
    """A state that calls a service.

    Signature of the ROS 2 smach_ros (the node first), plus ``server_wait_timeout``,
    ``call_timeout``, ``call_attempts``, ``liveness_period`` and ``peer_alive``. ``call_attempts``
    sends the request again when no answer came within ``call_timeout`` (for
    idempotent services: a request or response sent while DDS is still matching a
    freshly started server can be lost). ``peer_alive()``, if given, is checked with
    the server's presence in the graph every ``liveness_period``: two false answers
    in a row abort the call (the caller's own check of the server, e.g. a heartbeat,
    which does not wait for the DDS lease). Callbacks run in the executing thread:
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
        peer_alive: Callable[[], bool] | None = None,
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
        self._set_peer_alive(peer_alive)
        self._request = service_spec.Request() if request is None else request
        self._request_key = request_key
        self._request_slots = list(request_slots or ())
        self._response_key = response_key
        self._response_slots = list(response_slots or ())
        self._check_slots("request_slots", self._request_slots, service_spec.Request)
        self._check_slots("response_slots", self._response_slots, service_spec.Response)
        self._request_cb = self._callback(
            "request_cb", request_cb, request_cb_args, request_cb_kwargs
        )
        self._response_cb = self._callback(
            "response_cb", response_cb, response_cb_args, response_cb_kwargs
        )
        self._declare_keys(
            input_keys,
            output_keys,
            (request_key, self._request_slots),
            (response_key, self._response_slots),
        )

        helper = self._helper()
        self._resolved_name: str = node.resolve_service_name(service_name)
        self._client: Any = helper.node.create_client(
            service_spec, self._resolved_name, callback_group=helper.callback_group
        )
        self._helper_node: Any = helper.node

    def _ready(self) -> bool:
        return bool(self._client.service_is_ready())

    def execute(self, ud: smach.UserData) -> str:
        return self._guarded(lambda: self._execute(ud))

    def _execute(self, ud: smach.UserData) -> str:
        absent = self._wait_for_peer(
            self._ready, f"service {self._resolved_name!r}", self._server_wait_timeout
        )
        if absent is not None:
            return absent
        request = self._compose(
            ud,
            "request",
            self._request,
            self._request_key,
            self._request_slots,
            self._request_cb,
            self._spec.Request,
        )
        response = self._call(request)
        if isinstance(response, str):
            return response
        outcome = self._chosen_outcome("response_cb", self._response_cb, ud, response)
        self._store(ud, response, self._response_key, self._response_slots)
        if outcome == "preempted":
            self.service_preempt()
        return outcome or "succeeded"

    def _call(self, request: Any) -> Any:
        """The response, or the outcome to return instead (a string), sending the
        request up to ``call_attempts`` times."""
        for attempt in range(1, self._call_attempts + 1):
            self._wake.clear()
            try:
                future = self._client.call_async(request)
            except Exception as exc:
                raise StateAbort(
                    f"calling {self._resolved_name!r} failed: {type(exc).__name__}: {exc}"
                ) from exc
            future.add_done_callback(lambda _: self._wake.set())
            response = self._await_response(future)
            if response is not _NO_ANSWER:
                return response
            if attempt < self._call_attempts:
                smach.logwarn(
                    f"{self.path or 'ServiceState'}: service {self._resolved_name!r} did not "
                    f"answer within {self._call_timeout} s; sending the request again "
                    f"(attempt {attempt + 1} of {self._call_attempts})"
                )
        raise StateAbort(
            f"service {self._resolved_name!r} did not answer within "
            f"{self._call_timeout} s (call_timeout)"
            + (f", {self._call_attempts} attempts" if self._call_attempts > 1 else "")
        )

    def _await_response(self, future: Any) -> Any:
        """The response, the outcome to return instead (a string), or ``_NO_ANSWER``."""
        start = time.monotonic()
        deadline = None if self._call_timeout is None else start + self._call_timeout
        liveness = self._liveness(self._ready, self._liveness_period, start)
        while not future.done():
            if self.preempt_requested():
                self._client.remove_pending_request(future)
                return self._preempted()
            now = time.monotonic()
            if deadline is not None and now >= deadline:
                self._client.remove_pending_request(future)
                return _NO_ANSWER
            if liveness.lost(now):
                self._client.remove_pending_request(future)
                raise StateAbort(f"service {self._resolved_name!r} disappeared before answering")
            limits = [t for t in (deadline, liveness.next_check) if t is not None]
            self._wait(None if not limits else min(limits) - time.monotonic())
        try:
            return future.result()
        except Exception as exc:
            raise StateAbort(
                f"service {self._resolved_name!r} failed: {type(exc).__name__}: {exc}"
            ) from exc

    def destroy(self) -> None:
        """Release the service client (the state cannot execute afterwards)."""
        self._helper_node.destroy_client(self._client)
