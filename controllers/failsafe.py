"""What a dead client leaves the vehicle doing: the autopilot's offboard-loss parameters, checked at connect.

When the platform dies (SIGKILL, power, a kernel panic) nobody sends zero or a holding mode: the
autopilot's own failsafe decides how long the last velocity is flown. Measured (ARCHITECTURE.md,
"Autopilot facts"): PX4 holds after ``COM_OF_LOSS_T`` (1 s) and then does ``COM_OBL_RC_ACT``;
ArduCopter keeps a GUIDED velocity target for ``GUID_TIMEOUT`` (3 s by default), then stops.

The platform's rule: a stale command never lasts longer than ``max_t`` + 0.5 s. :func:`check_failsafe`
reads each parameter, sets the ones that break the rule (when allowed to), and reports what it found.
"""

from __future__ import annotations

import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any

from controllers.errors import ControllerError

logger = logging.getLogger(__name__)

STALE_MARGIN_S = 0.5
"""How much longer than ``max_t`` a dead platform's last command may be flown."""

TUNED_TIMEOUT_S = 1.0
"""The loss timeout set when the autopilot's is too long (PX4's default COM_OF_LOSS_T), capped by the limit."""

PX4_STOPPING_LOSS_ACTIONS = {0: "Position mode", 4: "Land mode", 5: "Hold mode"}
"""COM_OBL_RC_ACT values that stop the vehicle where it is (others fly home, drift, or cut the motors)."""

PX4_HOLD_ACTION = 5


@dataclass(frozen=True, slots=True)
class FailsafeParam:
    """One autopilot parameter and the rule it must follow.

    Attributes:
        name: the parameter's name.
        integer: INT32 (PX4 enums) rather than a float.
        problem: ``problem(value, limit_s)``: why ``value`` breaks the rule, or "" when it is fine.
        safe_value: ``safe_value(limit_s)``: the value set instead.
    """

    name: str
    integer: bool
    problem: Callable[[float, float], str]
    safe_value: Callable[[float], float]


def _timeout_problem(value: float, limit_s: float) -> str:
    if value <= 0 or value > limit_s:
        return f"flies a stale command for {value:g} s (more than max_t + {STALE_MARGIN_S:g} = {limit_s:g} s)"
    return ""


def _tuned_timeout(limit_s: float) -> float:
    return min(TUNED_TIMEOUT_S, limit_s)


def _loss_action_problem(value: float, limit_s: float) -> str:
    if int(value) in PX4_STOPPING_LOSS_ACTIONS:
        return ""
    return "does not stop the vehicle when the offboard client is lost (stopping: " + ", ".join(
        f"{k} {v}" for k, v in PX4_STOPPING_LOSS_ACTIONS.items()) + ")"


RULES: dict[str, tuple[FailsafeParam, ...]] = {
    "px4": (
        FailsafeParam("COM_OF_LOSS_T", False, _timeout_problem, _tuned_timeout),
        FailsafeParam("COM_OBL_RC_ACT", True, _loss_action_problem, lambda limit: PX4_HOLD_ACTION),
    ),
    "ardupilot": (FailsafeParam("GUID_TIMEOUT", False, _timeout_problem, _tuned_timeout),),
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
        read = self._plugin.get_param_int if param.integer else self._plugin.get_param_float
        return float(await self._bound(f"read {param.name}", lambda: read(param.name)))

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
        if self.changed:
            text += "; set " + ", ".join(f"{k} {old:g} -> {new:g}" for k, (old, new) in self.changed.items())
        return text


async def check_failsafe(autopilot: str, params: ParamAccess, limit_s: float, *, tune: bool) -> FailsafeReport:
    """Read the autopilot's offboard-loss parameters; set those that allow a longer stale command.

    Args:
        autopilot: ``"px4"``, ``"ardupilot"`` or ``"unknown"``.
        params: bounded parameter calls of the connected controller.
        limit_s: the longest a stale command may be flown (``max_t`` + :data:`STALE_MARGIN_S`).
        tune: set parameters that break the rule; when False they are only reported.

    Returns:
        The report; ``report.problems`` says, per parameter, what is wrong and what to do.
    """
    report = FailsafeReport(limit_s)
    rules = RULES.get(autopilot)
    if rules is None:
        report.problems.append(f"cannot check the offboard-loss failsafe of an {autopilot} autopilot "
                               "(PX4 and ArduPilot are known)")
        return report
    for param in rules:
        try:
            value = await params.get(param)
        except ControllerError as exc:
            report.problems.append(f"could not read {param.name}: {exc}")
            continue
        report.found[param.name] = value
        problem = param.problem(value, limit_s)
        if not problem:
            continue
        wanted = param.safe_value(limit_s)
        if tune:
            try:
                await params.set(param, wanted)
                now = await params.get(param)
            except ControllerError as exc:
                problem += f"; setting it to {wanted:g} failed: {exc}"
            else:
                if not param.problem(now, limit_s):
                    report.changed[param.name] = (value, now)
                    continue
                problem += f"; set to {wanted:g}, it still reads {now:g}"
        else:
            problem += " (tune_autopilot_failsafe is off)"
        report.problems.append(f"{param.name} = {value:g} {problem}: set {param.name} to {wanted:g}")
    logger.info("%s%s", report.summary(), "" if report.ok else "; problems: " + "; ".join(report.problems))
    return report
