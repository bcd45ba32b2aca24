"""The envelope's cost per vector: :meth:`Envelope.confine` with a 100-vertex polygon and a radius.

Vehicle positions all over the polygon (a field-like boundary, its radius jittered per vertex), some near the edge
and some outside, each with a random heading and a random vector: what the gate pays before every vector it sends
(issue 49's goal: p95 <= 0.2 ms). The height band and the battery floor are on too, as a first flight has them.

With ``--approaches N``: the overshoot on the built-in vehicle through the real platform (UavCore, MAVSDK, the
simulator): N approaches to a 5 m radius at the default max speed (1 m/s) from home, each on a random heading
(teleported back to home between them, with the truth channel), in a steady 1 m/s wind from a random direction;
how far beyond the radius the simulator's truth went (issue 49's goal: p95 <= 1.0 m).

Usage: python scripts/bench_envelope.py [--vectors 20000] [--approaches 20] > scripts/results/envelope.json
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import platform
import random
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from controllers.base import Telemetry  # noqa: E402
from tests.core.flight_helpers import flying_core, speed, wait_until  # noqa: E402
from tests.core.test_envelope_flight import pushing  # noqa: E402
from tests.flight.test_envelope import HOME, polygon_file  # noqa: E402
from uav_tui.config import EnvelopeConfig  # noqa: E402
from uav_tui.events import EventLog  # noqa: E402
from uav_tui.flight.envelope import Envelope  # noqa: E402

VERTICES = 100
GOAL_P95_MS = 0.2
RADIUS_M = 5.0
GOAL_OVERSHOOT_P95_M = 1.0


def field(rng: random.Random, radius_m: float = 150.0) -> list[tuple[float, float]]:
    """A star-shaped boundary of :data:`VERTICES` vertices: simple, with corners pointing both ways."""
    corners = []
    for i in range(VERTICES):
        angle = 2 * math.pi * i / VERTICES
        r = radius_m * rng.uniform(0.7, 1.0)
        corners.append((r * math.cos(angle), r * math.sin(angle)))
    return corners


async def approaches(count: int, rng: random.Random) -> dict[str, object]:
    """Beyond the radius (m, negative: stopped inside) per approach, on the simulator's truth."""
    beyond = []
    with tempfile.TemporaryDirectory() as folder:
        wind = rng.uniform(0, 2 * math.pi)
        async with flying_core(Path(folder), processor=pushing(Path(folder)), radius_m=RADIUS_M,
                               wind=f"{math.cos(wind):.3f},{math.sin(wind):.3f}") as core:
            await core.execute("f 1")
            for _ in range(count):
                core.truth.request({"cmd": "teleport", "n": 0.0, "e": 0.0, "yaw": rng.uniform(0, 360)})
                await asyncio.sleep(1.0)
                refused, farthest = core.gate.envelope.refused, 0.0

                def stopped(refused: int = refused) -> bool:
                    nonlocal farthest
                    state = core.truth.latest()
                    farthest = max(farthest, math.hypot(state["n"], state["e"]))
                    return core.gate.envelope.refused > refused + 5 and speed(state) < 0.05

                await core.execute("autonomy on")
                await wait_until(stopped, 60, "the vehicle to stop at the radius")
                await asyncio.sleep(1.0)  # the wind on a vehicle holding there
                farthest = max(farthest, math.hypot(core.truth.latest()["n"], core.truth.latest()["e"]))
                await core.execute("autonomy off")
                beyond.append(farthest - RADIUS_M)
    p95 = float(np.percentile(beyond, 95))
    return {"radius_m": RADIUS_M, "approaches": count, "wind_ms": 1.0,
            "beyond_m": {"p50": round(float(np.percentile(beyond, 50)), 3), "p95": round(p95, 3),
                         "max": round(max(beyond), 3)},
            "goal_p95_m": GOAL_OVERSHOOT_P95_M, "goal_met": p95 <= GOAL_OVERSHOOT_P95_M}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--vectors", type=int, default=20000)
    parser.add_argument("--approaches", type=int, default=0, help="overshoot flights on the built-in vehicle")
    args = parser.parse_args()
    rng = random.Random(49)
    with tempfile.TemporaryDirectory() as folder:
        path = polygon_file(Path(folder) / "field.geojson", field(rng))
        envelope = Envelope(EnvelopeConfig(polygon=str(path), radius_m=140.0, min_height_m=2.0), EventLog())
    envelope.set_home(HOME.lat_deg, HOME.lon_deg)
    cases = [(Telemetry(north_m=rng.uniform(-160, 160), east_m=rng.uniform(-160, 160), yaw_deg=rng.uniform(0, 360),
                        rel_alt_m=10.0, battery_pct=80.0, roll_deg=1.0, pitch_deg=1.0),
              (rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.1, 2.0))) for _ in range(args.vectors)]
    costs_ms, outcomes = [], {"as asked": 0, "cut or slid": 0, "refused": 0}
    for telemetry, vector in cases:
        start = time.perf_counter_ns()
        confined = envelope.confine(vector, telemetry)
        costs_ms.append((time.perf_counter_ns() - start) / 1e6)
        outcomes["refused" if confined.vector is None else "cut or slid" if confined.note else "as asked"] += 1
    p95 = float(np.percentile(costs_ms, 95))
    print(json.dumps({
        "benchmark": "envelope", "machine": platform.machine(), "python": platform.python_version(),
        "polygon_vertices": VERTICES, "vectors": args.vectors, "outcomes": outcomes,
        "confine_ms": {"p50": round(float(np.percentile(costs_ms, 50)), 4), "p95": round(p95, 4),
                       "max": round(max(costs_ms), 4)},
        "goal_p95_ms": GOAL_P95_MS, "goal_met": p95 <= GOAL_P95_MS,
        "overshoot": asyncio.run(approaches(args.approaches, rng)) if args.approaches else None}, indent=2))


if __name__ == "__main__":
    main()
