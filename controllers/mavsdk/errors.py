"""The one place where MAVSDK's errors become uav-tui's (like httpx's ``map_httpcore_exceptions``).

Every MAVSDK plugin raises its own ``<Plugin>Error`` carrying a ``result`` enum; the enums share
their member names (``COMMAND_DENIED``, ``BUSY``, ``TIMEOUT``, ``UNSUPPORTED``, ...), so the
translation goes by name.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Callable, Iterator

from mavsdk.asyncio import MavsdkError

from controllers.errors import CommandDenied, ControllerError, LinkLost, NotSupported

logger = logging.getLogger(__name__)

LINK_RESULTS = frozenset({"NO_SYSTEM", "CONNECTION_ERROR"})
"""Results that mean the autopilot is not reachable at all."""

UNSUPPORTED_RESULTS = frozenset({"UNSUPPORTED", "NO_VTOL_TRANSITION_SUPPORT"})

LINK_STALE_S = 3.0
"""A timed-out command while the heartbeat is older than this is reported as a lost link."""

HINTS: dict[tuple[str, str], str] = {
    ("arm", "COMMAND_DENIED"): "check the pre-arm messages (GPS fix, health, mode, safety switch)",
    ("disarm", "COMMAND_DENIED"): "the vehicle is probably in the air: land first",
    ("disarm", "COMMAND_DENIED_NOT_LANDED"): "the vehicle is in the air: land first",
    ("takeoff", "COMMAND_DENIED"): "arm first, and wait for a position estimate (GPS fix)",
    ("set_fly_vector", "COMMAND_DENIED"): "offboard needs an armed vehicle with a position estimate",
}
"""What to do next, by (command, result)."""


def result_name(exc: BaseException) -> str:
    """The name of a MAVSDK error's result enum (``"COMMAND_DENIED"``), or ``"UNKNOWN"``."""
    result = getattr(exc, "result", None)
    return getattr(result, "name", None) or (str(result) if result is not None else "UNKNOWN")


def translate(command: str, exc: BaseException, heartbeat_age_s: Callable[[], float] | None = None) -> ControllerError:
    """Translate one MAVSDK (or timeout) exception raised by ``command`` into a ControllerError.

    Args:
        command: our command name (``"arm"``, ``"takeoff"``, ...), kept on the error.
        exc: what MAVSDK raised, or ``TimeoutError`` from our own bound on the call.
        heartbeat_age_s: when given, a timeout with a stale heartbeat becomes :class:`LinkLost`.
    """
    if isinstance(exc, TimeoutError):
        result = "TIMEOUT"
    elif isinstance(exc, MavsdkError):
        result = result_name(exc)
    else:
        return ControllerError(f"{command} failed: {exc}")
    age = heartbeat_age_s() if heartbeat_age_s is not None else 0.0
    if result in LINK_RESULTS or (result == "TIMEOUT" and age > LINK_STALE_S):
        return LinkLost(
            f"{command} failed ({result}): no link to the autopilot (last heartbeat {age:.1f} s ago); "
            "check the cable / radio"
        )
    if result in UNSUPPORTED_RESULTS:
        return NotSupported(f"{command} is not supported by this autopilot ({result})")
    hint = HINTS.get((command, result))
    if hint is None and result == "TIMEOUT":
        hint = "the autopilot did not answer in time; try again"
    message = f"{command} refused by the autopilot ({result})" + (f": {hint}" if hint else "")
    return CommandDenied(message, command=command, result=result)


@contextlib.contextmanager
def map_mavsdk_errors(command: str, heartbeat_age_s: Callable[[], float] | None = None) -> Iterator[None]:
    """Re-raise MAVSDK errors (and timeouts) raised inside the block as uav-tui ControllerErrors.

    Example::

        with map_mavsdk_errors("arm", self.heartbeat_age_s):
            await self._action.arm()
    """
    try:
        yield
    except (MavsdkError, TimeoutError) as exc:
        raise translate(command, exc, heartbeat_age_s) from exc
    except RuntimeError as exc:
        # MAVSDK's handle checks ("System has been destroyed") after close().
        if "destroyed" in str(exc):
            raise ControllerError(f"{command}: the flight controller connection is closed") from exc
        raise
