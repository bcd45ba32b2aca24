"""The envelope's cost per vector: :meth:`Envelope.confine` with a 100-vertex polygon and a radius.

Vehicle positions all over the polygon (a field-like boundary, its radius jittered per vertex), some near the edge
and some outside, each with a random heading and a random vector: what the gate pays before every vector it sends
(issue 49's goal: p95 <= 0.2 ms). The height band and the battery floor are on too, as a first flight has them.

Usage: python scripts/bench_envelope.py [--vectors 20000] > scripts/results/envelope.json
"""

from __future__ import annotations

import argparse
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
from tests.flight.test_envelope import HOME, polygon_file  # noqa: E402
from uav_tui.config import EnvelopeConfig  # noqa: E402
from uav_tui.events import EventLog  # noqa: E402
from uav_tui.flight.envelope import Envelope  # noqa: E402

VERTICES = 100
GOAL_P95_MS = 0.2


def field(rng: random.Random, radius_m: float = 150.0) -> list[tuple[float, float]]:
    """A star-shaped boundary of :data:`VERTICES` vertices: simple, with corners pointing both ways."""
    corners = []
    for i in range(VERTICES):
        angle = 2 * math.pi * i / VERTICES
        r = radius_m * rng.uniform(0.7, 1.0)
        corners.append((r * math.cos(angle), r * math.sin(angle)))
    return corners


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--vectors", type=int, default=20000)
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
        "goal_p95_ms": GOAL_P95_MS, "goal_met": p95 <= GOAL_P95_MS}, indent=2))


if __name__ == "__main__":
    main()
