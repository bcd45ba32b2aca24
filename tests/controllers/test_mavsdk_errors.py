"""MAVSDK results become uav-tui errors at one boundary."""

from __future__ import annotations

import pytest
from mavsdk.asyncio.plugins.action import ActionError, ActionResult
from mavsdk.asyncio.plugins.offboard import OffboardError, OffboardResult

from controllers.mavsdk.errors import map_mavsdk_errors
from uav_tui.errors import CommandDenied, ControllerError, LinkLost, NotSupported


@pytest.mark.parametrize(
    ("exc", "heartbeat_age", "kind", "result"),
    [
        pytest.param(
            ActionError(ActionResult.COMMAND_DENIED, "arm()"),
            0.1,
            CommandDenied,
            "COMMAND_DENIED",
            id="denied",
        ),
        pytest.param(ActionError(ActionResult.BUSY, "takeoff()"), 0.1, CommandDenied, "BUSY", id="busy"),
        pytest.param(
            ActionError(ActionResult.TIMEOUT, "land()"), 0.1, CommandDenied, "TIMEOUT", id="timeout-link-ok"
        ),
        pytest.param(TimeoutError(), 0.1, CommandDenied, "TIMEOUT", id="our-bound"),
        pytest.param(
            OffboardError(OffboardResult.NO_SETPOINT_SET, "start()"),
            0.1,
            CommandDenied,
            "NO_SETPOINT_SET",
            id="offboard",
        ),
        pytest.param(
            ActionError(ActionResult.UNSUPPORTED, "do_orbit()"), 0.1, NotSupported, None, id="unsupported"
        ),
        pytest.param(ActionError(ActionResult.NO_SYSTEM, "arm()"), 0.1, LinkLost, None, id="no-system"),
        pytest.param(
            ActionError(ActionResult.TIMEOUT, "hold()"), 5.0, LinkLost, None, id="timeout-link-stale"
        ),
    ],
)
def test_results_map_to_our_errors(
    exc: Exception, heartbeat_age: float, kind: type, result: str | None
) -> None:
    with pytest.raises(kind) as info, map_mavsdk_errors("cmd", lambda: heartbeat_age):
        raise exc
    assert info.value.__cause__ is exc
    if result is not None:
        assert (info.value.command, info.value.result) == ("cmd", result)
        assert f"cmd refused by the autopilot ({result})" in str(info.value)


def test_hints_say_what_to_do() -> None:
    with (
        pytest.raises(CommandDenied, match="the vehicle is probably in the air: land first"),
        map_mavsdk_errors("disarm"),
    ):
        raise ActionError(ActionResult.COMMAND_DENIED, "disarm()")


def test_use_after_close_is_a_controller_error() -> None:
    with pytest.raises(ControllerError, match="connection is closed"), map_mavsdk_errors("arm"):
        raise RuntimeError(
            "System has been destroyed (its Mavsdk was destroyed, or destroy() was called explicitly)"
        )


def test_other_errors_pass_through() -> None:
    with pytest.raises(ValueError), map_mavsdk_errors("arm"):
        raise ValueError("bug")
