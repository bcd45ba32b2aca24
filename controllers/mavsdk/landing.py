"""Landing on the companion's target through MAVSDK: LANDING_TARGET stamped on the autopilot's clock, and the
precision landing that uses it (what each autopilot needs: :mod:`controllers.precland_requirements`)."""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Awaitable, Callable
from typing import Any

from mavsdk.asyncio.plugins.mavlink_direct import MavlinkMessage

from controllers.autopilots import Autopilot
from controllers.landing_target_message import LandingTargetError, LandingTargetFix, landing_target_fields
from controllers.mavsdk.attach import ReachedAutopilot
from controllers.mavsdk.calls import Command
from controllers.mavsdk.mavlink_commands import landing_target, px4_set_mode, send_command
from controllers.mavsdk.pose import BootClock
from controllers.precland_requirements import PrecisionLandingError, check_ardupilot_params


class MavsdkLanding:
    """LANDING_TARGET and precision landing for one autopilot reached through MAVSDK.

    Args:
        reached: the autopilot and its plugins.
        command: the controller's bounded, translated call.
    """

    def __init__(self, reached: ReachedAutopilot, command: Command) -> None:
        self.reached = reached
        self._command = command
        self.boot_clock = BootClock()
        """The autopilot's clock (``time_boot_ms`` of its ATTITUDE) against ours: LANDING_TARGET's time_usec."""

    def on_attitude(self, message: MavlinkMessage) -> None:
        """One ATTITUDE from any system (read for the autopilot's boot clock)."""
        received = time.monotonic_ns()
        if message.system_id != self.reached.sysid:
            return
        with contextlib.suppress(ValueError, KeyError, TypeError):
            self.boot_clock.observe(int(json.loads(message.fields_json)["time_boot_ms"]), received)

    async def send(self, fix: LandingTargetFix) -> dict[str, Any]:
        """Send LANDING_TARGET for a target seen in the frame captured at ``fix.capture_mono_ns``.

        Converted for this autopilot (:mod:`controllers.landing_target_message`: ArduPilot angles in BODY_FRD, PX4 the
        local NED position), ``time_usec`` the capture on the autopilot's clock (µs since its boot, mapped from
        its ATTITUDE messages). Returns the fields sent.

        Raises:
            LandingTargetError: the autopilot's clock is not known yet, or the fix can't be given to it.
            ControllerError: the send failed.
        """
        time_usec = self.boot_clock.boot_us(fix.capture_mono_ns)
        if time_usec is None:
            raise LandingTargetError("landing target: no ATTITUDE from the autopilot yet, so its clock is unknown: "
                                     "not sent")
        fields = landing_target_fields(self.reached.autopilot, fix, time_usec)
        message = landing_target(self.reached.sysid, fields)
        await self._command("landing_target", lambda: self.reached.direct.send_message(message))
        return fields

    async def precision_land(self, land: Callable[[], Awaitable[None]],
                             stop_and_hold: Callable[[], Awaitable[None]]) -> str:
        """Land on the landing target sent with :meth:`send`; returns what was done.

        ArduPilot: PLND_ENABLED and PLND_TYPE checked, then ``land()``; PX4: ``stop_and_hold()`` (a running vector
        ends), then its Precision Land mode.

        Raises:
            PrecisionLandingError: a PLND parameter missing or wrong (named, with the value it needs), or an
                autopilot that is neither PX4 nor ArduPilot.
            ControllerError: the landing was refused, or the link is lost.
        """
        reached = self.reached
        if reached.autopilot is Autopilot.ARDUPILOT:
            found = await check_ardupilot_params(
                lambda name: self._command(f"read {name}", lambda: reached.param.get_param_int(name)))
            await land()
            return "precision landing (LAND, " + ", ".join(f"{k}={v}" for k, v in found.items()) + ")"
        if reached.autopilot is not Autopilot.PX4:
            raise PrecisionLandingError(f"precland: {reached.autopilot.label}: only PX4 and ArduPilot "
                                        "are known to land on LANDING_TARGET")
        await stop_and_hold()
        command = px4_set_mode(reached.sysid, "PRECLAND")
        await self._command("precision land", lambda: send_command(reached.direct, command))
        return "precision landing (PX4's Precision Land mode)"
