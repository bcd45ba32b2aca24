"""Command latency: set_fly_vector() called -> first setpoint carrying that vector read by the vehicle.

Calling ``set_fly_vector`` stands in for ``getPreparedVector()`` returning (the autonomy gate adds
only its checks). The simulated vehicle stamps every SET_POSITION_TARGET_LOCAL_NED it reads with
``time.monotonic_ns()`` (same clock as ours on one machine); its truth channel returns the stamps.

Two cases:

- ``replace``: a vector is already running (a processor emitting vectors continuously): the new
  setpoint goes out at once, without leaving offboard.
- ``start_from_hold``: the first vector after HOLD: the setpoint goes out at once, then the
  controller streams ~0.1 s and switches to offboard; ``call_return_ms`` is when the call returns.

Also reports the setpoint rate seen by the vehicle while vectors are replaced every 0.15 s: our
20 Hz stream plus one immediate setpoint per replacement (MAVSDK re-sends nothing: setpoints go out
as raw MAVLink). Prints JSON.

Usage: python scripts/bench_command_latency.py [--replace 60] [--start 10]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import platform
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from controllers.mavsdk.controller import MavsdkController  # noqa: E402
from controllers.sim.launcher import SimVehicle  # noqa: E402
from controllers.sim.truth import TruthClient  # noqa: E402
from uav_tui.errors import CommandDenied  # noqa: E402


def summary(values_ms: list[float]) -> dict[str, Any]:
    ordered = sorted(values_ms)
    pick = lambda q: round(ordered[min(len(ordered) - 1, int(q * len(ordered)))], 3)  # noqa: E731
    return {"n": len(ordered), "p50_ms": pick(0.50), "p95_ms": pick(0.95), "max_ms": round(ordered[-1], 3)}


async def first_arrival(truth: TruthClient, since_ns: int, vx: float, vy: float) -> int:
    """Monotonic ns at which the vehicle first read a setpoint (vx, vy) after ``since_ns``."""
    for _ in range(50):
        reply = await asyncio.to_thread(truth.request, {"cmd": "setpoints", "since_mono_ns": since_ns}, 1.0)
        for rec in reply["records"]:
            if abs(rec["vx"] - vx) < 1e-4 and abs(rec["vy"] - vy) < 1e-4:
                return int(rec["t_mono_ns"])
        await asyncio.sleep(0.01)
    raise RuntimeError(f"setpoint ({vx}, {vy}) never arrived")


async def wait_state(truth: TruthClient, pred: Any, timeout: float) -> dict[str, Any]:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        state = truth.latest()
        if state is not None and "n" in state and pred(state):
            return state
        await asyncio.sleep(0.02)
    raise RuntimeError("the simulated vehicle did not get there in time")


async def fly_up(fc: MavsdkController, truth: TruthClient) -> None:
    deadline = time.monotonic() + 10
    while True:
        try:
            await fc.arm()
            break
        except CommandDenied:
            if time.monotonic() > deadline:
                raise
            await asyncio.sleep(0.3)
    await fc.takeoff(3.0)
    await wait_state(truth, lambda s: s["mode"] == "HOLD" and -s["d"] > 2.8, 15)


async def bench(replace_n: int, start_n: int) -> dict[str, Any]:
    sim = await asyncio.to_thread(SimVehicle().start)
    fc = MavsdkController()
    try:
        await fc.connect(sim.connection_string)
        truth = sim.truth()
        await fly_up(fc, truth)

        start_ms, return_ms = [], []
        for i in range(start_n):
            vx = round(0.2 + 0.001 * i, 4) * (1 if i % 2 == 0 else -1)
            t0 = time.monotonic_ns()
            await fc.set_fly_vector(vx, 0.0, 0.3)
            return_ms.append((time.monotonic_ns() - t0) / 1e6)
            start_ms.append((await first_arrival(truth, t0, vx, 0.0) - t0) / 1e6)
            while fc.vector_active:
                await asyncio.sleep(0.02)
            await wait_state(truth, lambda s: s["mode"] == "HOLD", 2)

        replace_ms = []
        rate_since = time.monotonic_ns()
        await fc.set_fly_vector(0.1, 0.0, 2.0)
        for i in range(replace_n):
            await asyncio.sleep(0.15)
            vy = round(0.1 + 0.001 * i, 4) * (1 if i % 2 == 0 else -1)
            t0 = time.monotonic_ns()
            await fc.set_fly_vector(0.0, vy, 2.0)
            replace_ms.append((await first_arrival(truth, t0, 0.0, vy) - t0) / 1e6)
        rate_until = time.monotonic_ns()
        records = []
        since = rate_since
        while True:
            reply = await asyncio.to_thread(truth.request, {"cmd": "setpoints", "since_mono_ns": since}, 1.0)
            records += [r for r in reply["records"] if r["t_mono_ns"] <= rate_until]
            if not reply["more"]:
                break
            since = reply["records"][-1]["t_mono_ns"]
        await fc.hold()
        seconds = (rate_until - rate_since) / 1e9
    finally:
        await fc.close()
        await asyncio.to_thread(sim.stop)
    return {
        "benchmark": "command_latency",
        "what": "set_fly_vector() call -> first setpoint with that vector read by the simulated vehicle",
        "replace": summary(replace_ms),
        "start_from_hold": summary(start_ms),
        "start_from_hold_call_return": summary(return_ms),
        "setpoints_per_s_while_streaming": round(len(records) / seconds, 1),
        "streamed_by_us_hz": 20.0,
        "machine": {"python": platform.python_version(), "cpu": platform.machine()},
    }


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--replace", type=int, default=60, help="replacement vectors to time")
    parser.add_argument("--start", type=int, default=10, help="vectors from HOLD to time")
    args = parser.parse_args()
    print(json.dumps(asyncio.run(bench(args.replace, args.start)), indent=2))


if __name__ == "__main__":
    main()
