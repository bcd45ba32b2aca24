"""What a dead client leaves the vehicle doing: the autopilot's offboard-loss parameters, checked at connect.

When the platform dies (SIGKILL, power, a kernel panic) nobody sends zero or a holding mode: the
autopilot's own failsafe decides how long the last velocity is flown, and what the vehicle does then.
Measured (docs/flight-controllers.md, "Measured autopilot facts"): PX4 switches after ``COM_OF_LOSS_T`` (1 s) to
``COM_OBL_RC_ACT``; ArduCopter keeps a GUIDED velocity target for ``GUID_TIMEOUT`` (3 s by default), then
stops in GUIDED.

The platform's rules: a stale command never lasts longer than ``max_t`` + 0.5 s, and what follows holds position
and height (or lands) whether or not a pilot is there. PX4's default Position mode (``COM_OBL_RC_ACT`` 0) flies
the sticks: with no radio PX4 v1.16 SITL sank from 4.9 m to 0.45 m in 8 s and drifted 0.13-0.3 m/s, so it is
accepted only while a radio is connected and read (:class:`Radio`). ArduCopter's lapsed target holds position
only while GUIDED stabilises it (``GUID_OPTIONS`` bits 4 and 5 clear). :func:`check_failsafe` reads each
parameter, sets the ones that break a rule (when allowed to), and reports what it found.
"""

from __future__ import annotations

import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any

from controllers.autopilots import Autopilot
from controllers.errors import ControllerError

logger = logging.getLogger(__name__)

STALE_MARGIN_S = 0.5
"""How much longer than ``max_t`` a dead platform's last command may be flown."""

TUNED_TIMEOUT_S = 1.0
"""The loss timeout set when the autopilot's is too long (PX4's default COM_OF_LOSS_T), capped by the limit."""

PX4_HOLDING_LOSS_ACTIONS = {4: "Land mode", 5: "Hold mode"}
"""COM_OBL_RC_ACT values that hold position and height, or land, with nobody at the sticks."""

PX4_POSITION_MODE = 0
"""COM_OBL_RC_ACT 0, Position mode: held by a pilot's centred sticks, accepted only with a :class:`Radio`."""

PX4_HOLD_ACTION = 5

PX4_STICKS_DISABLED = 4
"""COM_RC_IN_MODE 4: PX4 ignores every stick input."""

ARDUCOPTER_UNSTABILISED = 1 << 4 | 1 << 5
"""GUID_OPTIONS bits 4 "Do not stabilize PositionXY" and 5 "Do not stabilize VelocityXY": a lapsed GUIDED target
then stops correcting the position, and the vehicle drifts."""


@dataclass(frozen=True, slots=True)
class Radio:
    """Whether a pilot can fly PX4's Position mode: a radio present and configured.

    Attributes:
        receiver: PX4's SYS_STATUS says the RC receiver is *present* (and healthy): PX4 sets that bit only while a
            valid manual-control input (an RC transmitter, or a ground station's joystick) arrives within
            COM_RC_LOSS_T. The health bit alone says nothing: PX4 sets it for an absent receiver too. None: no
            SYS_STATUS arrived.
        rc_in_mode: COM_RC_IN_MODE (4: stick input disabled); None when it could not be read.
    """

    receiver: bool | None
    rc_in_mode: int | None

    @property
    def flies(self) -> bool:
        return bool(self.receiver) and self.rc_in_mode is not None and self.rc_in_mode != PX4_STICKS_DISABLED

    def describe(self) -> str:
        mode = "unreadable" if self.rc_in_mode is None else str(self.rc_in_mode)
        if self.flies:
            return f"radio connected (SYS_STATUS: RC receiver present; COM_RC_IN_MODE={mode})"
        receiver = {None: "no SYS_STATUS", False: "SYS_STATUS: no RC receiver"}.get(self.receiver,
                                                                               "SYS_STATUS: RC receiver present")
        return f"no radio ({receiver}; COM_RC_IN_MODE={mode})"


@dataclass(frozen=True, slots=True)
class Context:
    """What a rule is judged against: the longest stale command allowed, and the radio (PX4 only)."""

    limit_s: float
    radio: Radio | None = None


@dataclass(frozen=True, slots=True)
class FailsafeParam:
    """One autopilot parameter and the rule it must follow.

    Attributes:
        name: the parameter's name.
        integer: INT32 (PX4 enums, ArduPilot bitmasks) rather than a float.
        problem: ``problem(value, context)``: why ``value`` breaks the rule, or "" when it is fine.
        safe_value: ``safe_value(value, context)``: the value set instead.
    """

    name: str
    integer: bool
    problem: Callable[[float, Context], str]
    safe_value: Callable[[float, Context], float]


def _timeout_problem(value: float, context: Context) -> str:
    limit_s = context.limit_s
    if value <= 0 or value > limit_s:
        return f"flies a stale command for {value:g} s (more than max_t + {STALE_MARGIN_S:g} = {limit_s:g} s)"
    return ""


def _tuned_timeout(value: float, context: Context) -> float:
    return min(TUNED_TIMEOUT_S, context.limit_s)


def _loss_action_problem(value: float, context: Context) -> str:
    action = int(value)
    if action in PX4_HOLDING_LOSS_ACTIONS:
        return ""
    if action == PX4_POSITION_MODE:
        if context.radio is not None and context.radio.flies:
            return ""
        radio = context.radio.describe() if context.radio is not None else "no radio"
        return (f"is Position mode, which flies the sticks, and there is {radio}: with nobody at them PX4 sinks "
                "and drifts")
    return "does not hold or land the vehicle when the offboard client is lost (holding: " + ", ".join(
        f"{k} {v}" for k, v in PX4_HOLDING_LOSS_ACTIONS.items()) + f"; {PX4_POSITION_MODE} Position mode with a radio)"


def _guided_options_problem(value: float, context: Context) -> str:
    if int(value) & ARDUCOPTER_UNSTABILISED:
        return "stops GUIDED stabilising the position (bits 4/5): a lapsed target leaves the vehicle drifting"
    return ""


RULES: dict[Autopilot, tuple[FailsafeParam, ...]] = {
    Autopilot.PX4: (
        FailsafeParam("COM_OF_LOSS_T", False, _timeout_problem, _tuned_timeout),
        FailsafeParam("COM_OBL_RC_ACT", True, _loss_action_problem, lambda value, context: PX4_HOLD_ACTION),
    ),
    Autopilot.ARDUPILOT: (
        FailsafeParam("GUID_TIMEOUT", False, _timeout_problem, _tuned_timeout),
        FailsafeParam("GUID_OPTIONS", True, _guided_options_problem,
                      lambda value, context: int(value) & ~ARDUCOPTER_UNSTABILISED),
    ),
}
"""The parameters checked per autopilot (``MavsdkController.autopilot``)."""


Bound = Callable[[str, Callable[[], Awaitable[Any]]], Awaitable[Any]]
"""``bound(name, call)``: runs one MAVSDK call with a timeout, raising ControllerError."""


class ParamAccess:
    """Reads and writes parameters through MAVSDK's Param plugin, each call through ``bound``.

    Args:
        plugin: a ``ParamAsync`` (``get_param_float``, ``get_param_int``, ``set_param_float``, ``set_param_int``).
        bound: the controller's bounded-call wrapper.
    """

    def __init__(self, plugin: Any, bound: Bound) -> None:
        self._plugin = plugin
        self._bound = bound

    async def get(self, param: FailsafeParam) -> float:
        return await self.read(param.name, integer=param.integer)

    async def read(self, name: str, *, integer: bool) -> float:
        """One parameter's value (INT32 with ``integer``, else REAL32)."""
        read = self._plugin.get_param_int if integer else self._plugin.get_param_float
        return float(await self._bound(f"read {name}", lambda: read(name)))

    async def set(self, param: FailsafeParam, value: float) -> None:
        if param.integer:
            await self._bound(f"set {param.name}", lambda: self._plugin.set_param_int(param.name, int(value)))
        else:
            await self._bound(f"set {param.name}", lambda: self._plugin.set_param_float(param.name, value))


@dataclass(slots=True)
class FailsafeReport:
    """What :func:`check_failsafe` found and did.

    Attributes:
        found: parameter -> value read at connect.
        changed: parameter -> (old, new) for every parameter it set.
        problems: one sentence per parameter still breaking the rule (autonomy must stay off).
    """

    limit_s: float
    radio: str = ""
    """PX4: what says whether a pilot could fly Position mode (:meth:`Radio.describe`); "" elsewhere."""
    found: dict[str, float] = field(default_factory=dict)
    changed: dict[str, tuple[float, float]] = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems

    def summary(self) -> str:
        """One line: what was found, what was changed."""
        found = ", ".join(f"{k}={v:g}" for k, v in self.found.items()) or "nothing"
        text = f"autopilot failsafe: found {found}"
        if self.radio:
            text += f" ({self.radio})"
        if self.changed:
            text += "; set " + ", ".join(f"{k} {old:g} -> {new:g}" for k, (old, new) in self.changed.items())
        return text


async def check_failsafe(autopilot: Autopilot, params: ParamAccess, limit_s: float, *, tune: bool,
                         rc_receiver: Callable[[], Awaitable[bool | None]] | None = None) -> FailsafeReport:
    """Read the autopilot's offboard-loss parameters; set those that break a rule.

    Args:
        autopilot: the kind reached (another than PX4 or ArduPilot: reported as not checkable).
        params: bounded parameter calls of the connected controller.
        limit_s: the longest a stale command may be flown (``max_t`` + :data:`STALE_MARGIN_S`).
        tune: set parameters that break a rule; when False they are only reported.
        rc_receiver: PX4: asked whether SYS_STATUS shows the RC receiver present (see :class:`Radio`; None: no
            SYS_STATUS arrived).

    Returns:
        The report; ``report.problems`` says, per parameter, what is wrong and what to do.
    """
    report = FailsafeReport(limit_s)
    rules = RULES.get(autopilot)
    if rules is None:
        report.problems.append(f"cannot check the offboard-loss failsafe of an {autopilot} autopilot "
                               "(PX4 and ArduPilot are known)")
        return report
    context = Context(limit_s)
    if autopilot is Autopilot.PX4:
        receiver = await rc_receiver() if rc_receiver is not None else None
        context = Context(limit_s, Radio(receiver, await _rc_in_mode(params)))
        report.radio = context.radio.describe() if context.radio is not None else ""
    for param in rules:
        try:
            value = await params.get(param)
        except ControllerError as exc:
            report.problems.append(f"could not read {param.name}: {exc}")
            continue
        report.found[param.name] = value
        problem = param.problem(value, context)
        if not problem:
            continue
        wanted = param.safe_value(value, context)
        if tune:
            try:
                await params.set(param, wanted)
                now = await params.get(param)
            except ControllerError as exc:
                problem += f"; setting it to {wanted:g} failed: {exc}"
            else:
                if not param.problem(now, context):
                    report.changed[param.name] = (value, now)
                    continue
                problem += f"; set to {wanted:g}, it still reads {now:g}"
        else:
            problem += " (tune_autopilot_failsafe is off)"
        report.problems.append(f"{param.name} = {value:g} {problem}: set {param.name} to {wanted:g}")
    logger.info("%s%s", report.summary(), "" if report.ok else "; problems: " + "; ".join(report.problems))
    return report


async def _rc_in_mode(params: ParamAccess) -> int | None:
    """PX4's COM_RC_IN_MODE, or None when it cannot be read (then no radio is assumed)."""
    try:
        return int(await params.read("COM_RC_IN_MODE", integer=True))
    except ControllerError as exc:
        logger.warning("could not read COM_RC_IN_MODE (%s): taken as no radio", exc)
        return None
