"""Precision landing in the built-in simulator: landings on the sim: camera's marker from random offsets, in wind.

Each landing is a fresh run of the platform (UavCore) on the built-in simulator playing ArduCopter with
``PLND_ENABLED=1``: the ``precision_land`` processor in its own process, a ``sim:`` camera (640x480, 30 FPS, 62 deg)
with marker 7 (0.5 m) at a random offset up to ``--max-offset`` m from home (uniform over the disc), a steady
``--wind``. The vehicle takes off to ``--altitude`` m over home; ``precland`` once the marker is in view; touchdown
from the simulator's truth.

Measured: the landing error (the truth's position at touchdown against the marker's centre), the time from
``precland`` to touchdown, and for every LANDING_TARGET the simulator received (its own log, the arrival time on
the shared monotonic clock): capture -> arrival; the ``sim:`` camera's own delay (it stamps the capture at the pose
it renders, then renders: a real camera's readout); the processor's own time for that frame (``t_end - t_start``);
the platform's share, what is left, in three parts: the frame in the buffer to the processor's start, its end to
the send started on the event loop, that to the simulator's arrival (conversion, MAVSDK, UDP); and the
``time_usec`` stamp against the true capture time (its error, absolute). Also the relay's plausibility checks
(:mod:`uav_tui.flight.plausibility`) on every frame's landing target, in the loop thread's CPU time: where they run
(on the event loop, in flight: from cold caches on a loaded machine, shown beside an empty call timed the same way),
and on the flight's own inputs one after another (the code's cost: the goal); the gimbal pointing's check too.
Issue 38's goals: landing error p95 <= 0.25 m, the platform's share p95 <= 5 ms; issue 47's: the relay's checks
p95 <= 0.05 ms per frame.

Usage: python scripts/bench_precland.py [--landings 10] [--wind 3,2] [--altitude 10] [--max-offset 4] [--seed 0]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import os
import platform
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from controllers.autopilots import Autopilot  # noqa: E402
from controllers.sim.geo import parse_wind  # noqa: E402
from controllers.sim.launcher import SimVehicle  # noqa: E402
from controllers.sim.truth import TruthClient  # noqa: E402
from tests.core.flight_helpers import flying_core, wait_until  # noqa: E402
from uav_tui.flight.plausibility import LandingCheck, judge_gimbal  # noqa: E402
from uav_tui.relays.contract import HandledFrame  # noqa: E402
from uav_values.gimbal import GimbalPointing  # noqa: E402

MARKER_ID = 7
MARKER_SIZE_M = 0.5
GOAL_ERROR_P95_M = 0.25
GOAL_PLATFORM_P95_MS = 5.0
GOAL_CHECKS_P95_MS = 0.05


@dataclass
class Landing:
    """One landing's measurements."""

    pad_ne: tuple[float, float]
    error_m: float = math.nan
    precland_to_touchdown_s: float = math.nan
    latency_ms: list[float] = field(default_factory=list)
    processor_ms: list[float] = field(default_factory=list)
    platform_ms: list[float] = field(default_factory=list)
    camera_ms: list[float] = field(default_factory=list)
    handoff_ms: list[float] = field(default_factory=list)
    result_ms: list[float] = field(default_factory=list)
    send_ms: list[float] = field(default_factory=list)
    stamp_error_ms: list[float] = field(default_factory=list)
    check_ms: list[float] = field(default_factory=list)
    """The relay's plausibility check of each frame's landing target, in flight."""
    check_baseline_ms: list[float] = field(default_factory=list)
    check_inputs: list[tuple[Any, ...]] = field(default_factory=list)
    refusals: list[str] = field(default_factory=list)
    """What the relay refused (an honest processor's targets: each is a false refusal)."""
    targets_received: int = 0
    targets_unmatched: int = 0


def landing_targets(truth: TruthClient, since_mono_ns: int) -> list[dict[str, Any]]:
    """Every LANDING_TARGET the simulator received after ``since_mono_ns``, oldest first."""
    records: list[dict[str, Any]] = []
    while True:
        reply = truth.request({"cmd": "landing_targets", "since_mono_ns": since_mono_ns}, timeout=2.0)
        records += reply["records"]
        if not reply["more"]:
            return records
        since_mono_ns = records[-1]["t_mono_ns"]


async def land_once(pad_ne: tuple[float, float], wind: tuple[float, float], altitude: float, folder: Path) -> Landing:
    """Take off over home, ``precland`` on the marker at ``pad_ne``, and measure (see the module's docstring)."""
    landing = Landing(pad_ne)
    sent: dict[int, tuple[int, int, int]] = {}  # capture ns -> (t_start, t_end, on the loop) of each target sent
    published: dict[int, int] = {}  # capture ns -> when the frame reached the frame buffer (the sim: camera renders)

    def on_frame(result: HandledFrame) -> None:  # on the loop, right after the send was started
        if result.landing.startswith("refused: "):
            landing.refusals.append(result.landing)
        if result.landing == "sent":
            sent[result.frame.t_mono_ns] = (result.outcome.t_start_ns, result.outcome.t_end_ns, time.monotonic_ns())

    source = (f"sim:?marker={MARKER_ID}&marker_size={MARKER_SIZE_M:g}&marker_at={pad_ne[0]:.3f},{pad_ne[1]:.3f}")
    with SimVehicle(wind=wind, autopilot=Autopilot.ARDUPILOT, extra_args=["--plnd-enabled"]) as vehicle:
        async with flying_core(folder, vehicle=vehicle, altitude=altitude, source=source, processor="precision_land",
                               processor_args={"marker_id": MARKER_ID, "marker_size_m": MARKER_SIZE_M}) as core:
            truth: TruthClient = core.truth  # type: ignore[attr-defined]
            core.add_frame_listener(on_frame)
            time_checks(core.landing.check, landing)
            assert core.source is not None
            core.source.buffer.add_listener(lambda frame: published.__setitem__(frame.t_mono_ns, time.monotonic_ns()))
            await wait_until(lambda: core.landing.last_seen_ns is not None, 20, "the marker in view")
            started_ns = time.monotonic_ns()
            await core.execute("precland")
            boot_ns: list[int] = []  # the simulator's boot on the monotonic clock, from each truth sample
            state: dict[str, Any] = {}
            while True:  # polled, never waited on: the loop is the platform's
                await asyncio.sleep(0.01)
                newest = truth.latest()
                if newest is None or newest is state:
                    continue
                state = newest
                boot_ns.append(state["t_mono_ns"] - state["time_boot_ms"] * 1_000_000)
                if not state["in_air"] and state["d"] > -0.05:
                    break
                if state["t_mono_ns"] - started_ns > 120e9:
                    raise TimeoutError(f"no touchdown 120 s after precland (truth: {state})")
            landing.precland_to_touchdown_s = (state["t_mono_ns"] - started_ns) / 1e9
            landing.error_m = math.hypot(state["n"] - pad_ne[0], state["e"] - pad_ne[1])
            records = await asyncio.to_thread(landing_targets, truth, started_ns)
    # time_boot_ms is floored to the millisecond: the smallest difference is the boot
    split_latencies(landing, records, min(boot_ns), sent, published)
    return landing


def time_checks(check: Any, landing: Landing) -> None:
    """Time each call of ``check.judge`` (the relay's plausibility check, as the relay calls it, on the loop) in ms of
    the loop thread's own CPU time, and an empty call timed the same way beside it (on a loaded machine every call
    after the loop waited runs from cold caches); keep the inputs for :func:`replayed_check_ms`."""
    judge = check.judge

    def timed(*args: Any) -> Any:
        start = time.thread_time_ns()
        landing.check_baseline_ms.append((time.thread_time_ns() - start) / 1e6)
        start = time.thread_time_ns()
        try:
            return judge(*args)
        finally:
            landing.check_ms.append((time.thread_time_ns() - start) / 1e6)
            landing.check_inputs.append(args)

    check.judge = timed


def replayed_check_ms(inputs: list[tuple[Any, ...]], rounds: int = 20) -> list[float]:
    """The same checks on the flight's own inputs, one after another (``rounds`` times each, a fresh check each
    round): the code's cost without the machine's other work in between."""
    times = []
    for _ in range(rounds):
        check = LandingCheck()
        for args in inputs:
            start = time.thread_time_ns()
            check.judge(*args)
            times.append((time.thread_time_ns() - start) / 1e6)
    return times


def gimbal_check_ms(count: int = 20_000) -> list[float]:
    """The gimbal pointing's check, ``count`` times (it has no geometry: the copy and the contract's ranges)."""
    pointing, times = GimbalPointing.angles(-45.0, 10.0), []
    for _ in range(count):
        start = time.thread_time_ns()
        judge_gimbal(pointing)
        times.append((time.thread_time_ns() - start) / 1e6)
    return times


def split_latencies(landing: Landing, records: list[dict[str, Any]], boot_ns: int,
                    sent: dict[int, tuple[int, int, int]], published: dict[int, int]) -> None:
    """Each LANDING_TARGET the simulator received, matched to the frame it came from by its ``time_usec`` (the
    simulator boots at ``boot_ns``, monotonic), split into the camera's, the processor's and the platform's parts."""
    captures = np.array(sorted(sent), dtype=np.int64)
    landing.targets_received = len(records)
    for record in records:
        stamped = boot_ns + record["time_usec"] * 1000
        nearest = int(captures[np.argmin(np.abs(captures - stamped))]) if len(captures) else None
        if nearest is None or abs(nearest - stamped) > 10e6 or nearest not in published:  # frames are 33 ms apart
            landing.targets_unmatched += 1
            continue
        start, end, loop = sent[nearest]
        latency = (record["t_mono_ns"] - nearest) / 1e6
        camera = (published[nearest] - nearest) / 1e6
        landing.camera_ms.append(camera)
        landing.handoff_ms.append((start - published[nearest]) / 1e6)
        landing.result_ms.append((loop - end) / 1e6)
        landing.send_ms.append((record["t_mono_ns"] - loop) / 1e6)
        landing.latency_ms.append(latency)
        landing.processor_ms.append((end - start) / 1e6)
        landing.platform_ms.append(latency - (end - start) / 1e6 - camera)
        landing.stamp_error_ms.append(abs(stamped - nearest) / 1e6)

def pooled(landings: list[Landing], name: str) -> list[float]:
    return [value for landing in landings for value in getattr(landing, name)]


def stats(values: list[float], unit: str, digits: int = 3) -> dict[str, float]:
    array = np.asarray(values, dtype=float)
    return {f"p50_{unit}": round(float(np.percentile(array, 50)), digits),
            f"p95_{unit}": round(float(np.percentile(array, 95)), digits),
            f"max_{unit}": round(float(array.max()), digits)}


def goal(value: float, bound: float) -> dict[str, Any]:
    return {"goal": f"<= {bound:g}", "value": round(value, 3), "pass": bool(value <= bound)}


def offsets(count: int, max_offset: float, seed: int) -> list[tuple[float, float]]:
    """``count`` (north, east) offsets uniform over the disc of radius ``max_offset``."""
    rng = np.random.default_rng(seed)
    radius = max_offset * np.sqrt(rng.uniform(0, 1, count))
    bearing = rng.uniform(0, 2 * math.pi, count)
    return [(float(r * math.cos(b)), float(r * math.sin(b))) for r, b in zip(radius, bearing, strict=True)]


async def bench(args: argparse.Namespace) -> dict[str, Any]:
    landings: list[Landing] = []
    with tempfile.TemporaryDirectory() as folder:
        for pad_ne in offsets(args.landings, args.max_offset, args.seed):
            landings.append(await land_once(pad_ne, args.wind, args.altitude, Path(folder)))
            done = landings[-1]
            print(f"pad {done.pad_ne[0]:+.2f},{done.pad_ne[1]:+.2f}: {done.error_m:.3f} m in "
                  f"{done.precland_to_touchdown_s:.1f} s, {done.targets_received} targets", file=sys.stderr)
    errors = [landing.error_m for landing in landings]
    error = stats(errors, "m")
    share = stats(pooled(landings, "platform_ms"), "ms", 2)
    checks = stats(replayed_check_ms(pooled(landings, "check_inputs")), "ms", 4)
    return {
        "benchmark": "precland", "machine": platform.machine(), "cpus": os.cpu_count(),
        "load_average_1min_at_end": round(os.getloadavg()[0], 1), "python": platform.python_version(),
        "simulator": "built-in, ArduCopter dialect, PLND_ENABLED=1", "landings": len(landings),
        "altitude_m": args.altitude, "max_offset_m": args.max_offset, "wind_ne_ms": list(args.wind),
        "wind_speed_ms": round(math.hypot(*args.wind), 2), "seed": args.seed,
        "camera": "sim: 640x480, 30 FPS, hfov 62 deg, down", "marker": f"4x4_50 id {MARKER_ID}, {MARKER_SIZE_M} m",
        "landing_error": error,
        "precland_to_touchdown": stats([landing.precland_to_touchdown_s for landing in landings], "s", 1),
        "landing_targets_received": sum(landing.targets_received for landing in landings),
        "landing_targets_unmatched": sum(landing.targets_unmatched for landing in landings),
        "capture_to_landing_target": stats(pooled(landings, "latency_ms"), "ms", 2),
        "sim_camera_render": stats(pooled(landings, "camera_ms"), "ms", 2),
        "processor_own_time": stats(pooled(landings, "processor_ms"), "ms", 2),
        "platform_share": share,
        "platform_share_parts": {
            "frame_published_to_processor_start": stats(pooled(landings, "handoff_ms"), "ms", 2),
            "processor_end_to_send_started": stats(pooled(landings, "result_ms"), "ms", 2),
            "send_started_to_autopilot": stats(pooled(landings, "send_ms"), "ms", 2)},
        "time_usec_stamp_off_capture": stats(pooled(landings, "stamp_error_ms"), "ms", 2),
        "relay_checks": {
            "landing_target": checks | {"frames": len(pooled(landings, "check_ms")),
                                        "refused": pooled(landings, "refusals")},
            "landing_target_in_flight_cold": stats(pooled(landings, "check_ms"), "ms", 4),
            "empty_call_in_flight_cold": stats(pooled(landings, "check_baseline_ms"), "ms", 4),
            "gimbal_pointing": stats(gimbal_check_ms(), "ms", 4)},
        "per_landing": [{"pad_ne_m": [round(c, 2) for c in landing.pad_ne], "error_m": round(landing.error_m, 3),
                         "precland_to_touchdown_s": round(landing.precland_to_touchdown_s, 1)}
                        for landing in landings],
        "goals": {"landing error p95 (m)": goal(error["p95_m"], GOAL_ERROR_P95_M),
                  "capture to LANDING_TARGET over the processor's and the camera's own time, p95 (ms)":
                      goal(share["p95_ms"], GOAL_PLATFORM_P95_MS),
                  "the relay's plausibility checks of a frame's landing target, p95 (ms)":
                      goal(checks["p95_ms"], GOAL_CHECKS_P95_MS)},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--landings", type=int, default=10)
    parser.add_argument("--wind", type=parse_wind, default=(3.0, 2.0), metavar="N,E",
                        help="steady wind on the simulated vehicle, m/s (default 3,2: 3.6 m/s; 0,0 for still air)")
    parser.add_argument("--altitude", type=float, default=10.0, help="take-off height, m")
    parser.add_argument("--max-offset", type=float, default=4.0, help="largest marker offset from home, m")
    parser.add_argument("--seed", type=int, default=0, help="seed of the marker offsets")
    args = parser.parse_args()
    print(json.dumps(asyncio.run(bench(args)), indent=1))


if __name__ == "__main__":
    main()
