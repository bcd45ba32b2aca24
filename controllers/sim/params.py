"""The few PX4 parameters the simulator serves (those MAVSDK's action plugin reads and writes, and the
ones that tune the simulated behaviours). Values live in the simulator's config objects; a parameter
is a named getter/setter pair over them. Integers use PX4's bytewise encoding in PARAM_VALUE."""

from __future__ import annotations

import logging
import math
import struct
from collections.abc import Callable
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink

logger = logging.getLogger(__name__)

REAL32 = mavlink.MAV_PARAM_TYPE_REAL32
INT32 = mavlink.MAV_PARAM_TYPE_INT32


@dataclass(slots=True)
class Param:
    """One parameter: its type and how to read and write the value it stands for."""

    name: str
    kind: int
    get: Callable[[], float]
    set: Callable[[float], None] | None = None


def _constant(value: float) -> Callable[[], float]:
    return lambda: value


def encode_value(param: Param) -> float:
    """The float carried in PARAM_VALUE.param_value (int32 bits reinterpreted, PX4 style)."""
    value = param.get()
    if param.kind == INT32:
        return struct.unpack("<f", struct.pack("<i", int(value)))[0]
    return float(value)


def decode_value(kind: int, wire: float) -> float:
    """Inverse of :func:`encode_value` for PARAM_SET."""
    if kind == INT32:
        return float(struct.unpack("<i", struct.pack("<f", wire))[0])
    return float(wire)


class ParamStore:
    """Ordered parameters by name (PX4 names, at most 16 characters)."""

    def __init__(self, params: list[Param]) -> None:
        self._params = {p.name: p for p in params}
        self._order = [p.name for p in params]

    @classmethod
    def constants(cls, **values: float) -> list[Param]:
        """Read-only parameters; ints become INT32, floats REAL32."""
        return [Param(k, INT32 if isinstance(v, int) else REAL32, _constant(v)) for k, v in values.items()]

    @classmethod
    def settable(cls, **values: float) -> list[Param]:
        """Parameters kept as set (nothing the simulator does reads them); ints become INT32, floats REAL32."""
        store = dict(values)

        def kept(name: str, value: float) -> Param:
            return Param(name, INT32 if isinstance(value, int) else REAL32, lambda: store[name],
                         lambda new: store.__setitem__(name, new))

        return [kept(name, value) for name, value in values.items()]

    def __len__(self) -> int:
        return len(self._order)

    def lookup(self, name: str, index: int) -> tuple[int, Param] | None:
        """By name, or by index when ``index`` >= 0 (PARAM_REQUEST_READ semantics)."""
        if index >= 0:
            return (index, self._params[self._order[index]]) if index < len(self._order) else None
        if name in self._params:
            return self._order.index(name), self._params[name]
        return None

    def all(self) -> list[tuple[int, Param]]:
        return [(i, self._params[n]) for i, n in enumerate(self._order)]

    def set(self, name: str, wire_value: float) -> tuple[int, Param] | None:
        """Apply PARAM_SET; read-only or unknown parameters are left as they are (PX4 echoes them)."""
        found = self.lookup(name, -1)
        if found is None:
            logger.info("ParamStore: PARAM_SET for unknown %s ignored", name)
            return None
        _, param = found
        value = decode_value(param.kind, wire_value)
        if param.set is not None and math.isfinite(value):
            param.set(value)
            logger.info("ParamStore: %s = %s", name, value)
        return found
