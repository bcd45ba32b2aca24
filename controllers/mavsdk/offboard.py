"""Velocity control through MAVSDK, the autopilot side of :class:`~controllers.mavsdk.vector_stream.VectorStream`: each
setpoint, and the switches into and out of the velocity-control mode on PX4 and ArduCopter."""

from __future__ import annotations

import math
from typing import Protocol

from controllers.autopilots import Autopilot
from controllers.errors import ControllerError
from controllers.mavsdk import ardupilot
from controllers.mavsdk.attach import ReachedAutopilot
from controllers.mavsdk.calls import Command, Subscriptions
from controllers.mavsdk.height_hold import HeightHold
from controllers.mavsdk.mavlink_commands import px4_set_mode, send_command, velocity_body_setpoint


class ModeWatch(Protocol):
    """What velocity control reads of its controller: the mode last reported, and the modes that are its own."""

    def flight_mode_since(self, t_mono: float) -> str | None: ...

    @property
    def own_modes(self) -> frozenset[str]: ...


class MavsdkOffboard:
    """The :class:`~controllers.mavsdk.vector_stream.OffboardPort` of a MAVSDK controller, once :attr:`reached` is set.

    Args:
        modes: the controller: the mode the vehicle reports, and the modes its vectors and holds leave it in.
        command: the controller's bounded, translated call.
    """

    def __init__(self, modes: ModeWatch, command: Command) -> None:
        self._modes = modes
        self._command = command
        self.reached: ReachedAutopilot | None = None
        """The autopilot and its plugins (set by :meth:`attach` once the controller is connected)."""
        self.height: HeightHold | None = None
        """The height held while velocity control is engaged (set by :meth:`attach`)."""

    def attach(self, reached: ReachedAutopilot, subscriptions: Subscriptions) -> None:
        """The controller connected: drive ``reached``, and follow its height until ``subscriptions`` close."""
        self.reached = reached
        self.height = HeightHold(reached.sysid)
        self.height.follow(reached.direct, subscriptions)

    def flight_mode_since(self, t_mono: float) -> str | None:
        return self._modes.flight_mode_since(t_mono)

    async def guided(self, command: str) -> None:
        """ArduCopter: switch to GUIDED first (arming, take-off and velocity targets need it)."""
        if self.reached is not None and self.reached.autopilot is Autopilot.ARDUPILOT:
            await self._ardupilot_mode(self.reached, "GUIDED", command)

    async def send_velocity_body(self, forward_ms: float, right_ms: float) -> None:
        reached = self._connected("set_fly_vector")
        down_ms = self.height.vertical_speed() if self.height is not None else 0.0
        setpoint = velocity_body_setpoint(reached.sysid, forward_ms, right_ms, down_ms)
        await self._command("set_fly_vector", lambda: reached.direct.send_message(setpoint))

    async def start_offboard(self, *, yield_to_others: bool = False) -> None:
        """Switch to velocity control; with ``yield_to_others``, not from a mode someone else chose.

        Raises:
            ControllerError: ``yield_to_others`` and the vehicle reports a mode that is not the platform's (a pilot
                switched it as the vector was sent, a mission, a failsafe): their mode wins, it is not taken back.
        """
        mode = self._modes.flight_mode_since(-math.inf)
        if yield_to_others and mode is not None and mode not in self._modes.own_modes:
            raise ControllerError(f"the vehicle is in {mode} mode (a pilot, a mission or a failsafe chose it): "
                                  "not taken back")
        reached = self._connected("set_fly_vector")
        if reached.autopilot is Autopilot.ARDUPILOT:
            # GUIDED takes velocity targets; they must be renewed within GUID_TIMEOUT (3 s).
            await self._ardupilot_mode(reached, "GUIDED", "set_fly_vector")
        else:
            # PX4 accepts OFFBOARD only while setpoints stream (VectorStream streams first).
            command = px4_set_mode(reached.sysid, "OFFBOARD")
            await self._command("set_fly_vector", lambda: send_command(reached.direct, command))
        if self.height is not None:
            self.height.engage()

    async def stop_offboard(self) -> None:
        reached = self._connected("hold")
        if self.height is not None:
            self.height.release()
        if reached.autopilot is Autopilot.ARDUPILOT:  # not LOITER: it flies the RC throttle (see ardupilot.hold)
            await self._command("hold", lambda: ardupilot.hold(reached.direct, reached.sysid))
        else:  # PX4 HOLD (Auto Loiter): automatic, the sticks only matter when a pilot moves them to take over
            await self._command("hold", reached.action.hold)

    async def _ardupilot_mode(self, reached: ReachedAutopilot, mode: str, command: str) -> None:
        await self._command(command, lambda: ardupilot.set_mode(reached.direct, reached.sysid, mode))

    def _connected(self, name: str) -> ReachedAutopilot:
        if self.reached is None:
            raise ControllerError(f"{name}: not connected (call connect() first)")
        return self.reached
