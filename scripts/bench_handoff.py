"""The Python cost of handing one frame to the processor's process and its result back, step by step.

Both sides run in this one process and thread, in the order they run in flight, so what is measured is
the code itself (locks, syscalls, encoding), without wake-ups or scheduling: the floor of what process
isolation adds to every frame. ``bench_pipeline.py`` measures the whole pipeline. Prints one JSON object,
microseconds per frame for each step.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from multiprocessing import Pipe, resource_tracker
from multiprocessing.shared_memory import SharedMemory
from pathlib import Path
from types import SimpleNamespace

import msgspec

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from processors.base import ProcessorInfo  # noqa: E402
from uav_tui.hosting.child import ChildRunner  # noqa: E402
from uav_tui.hosting.codec import decode_from_child  # noqa: E402
from uav_tui.hosting.frame_mailbox import FrameMailbox, Offer  # noqa: E402
from uav_tui.hosting.pipe import Inbox, send_message  # noqa: E402

SHAPE = (480, 640, 3)


class DoesNothing:
    def photo_processing(self, frame: object) -> None:
        pass

    def getPreparedVector(self) -> tuple[float, float, float]:  # noqa: N802 - the published contract's name
        return 0.0, 0.0, 0.0


def measure(frames: int) -> dict[str, float]:
    platform_box = FrameMailbox.create()
    # The child's side attaches by name as the child does; here, in the same process, that unregisters the
    # segments from this process's resource tracker, so they are registered again before they are unlinked.
    child_box = FrameMailbox.attach(platform_box.address)
    slot = SharedMemory(create=True, size=SHAPE[0] * SHAPE[1] * SHAPE[2])
    platform_end, child_end = Pipe()
    inbox = Inbox(platform_end)
    info = ProcessorInfo("bench", None, frozenset({"getPreparedVector"}))
    runner = ChildRunner(child_end, child_box, SimpleNamespace(instance=DoesNothing(), info=info))
    telemetry = msgspec.msgpack.encode({"armed": True, "relative_alt_m": 10.0, "lat_deg": 47.39, "lon_deg": 8.54})
    steps = dict.fromkeys(("platform_offer", "child_poll_messages", "child_claim", "child_process_wrapper",
                           "child_send_result", "platform_read_result"), 0)
    try:
        for gen in range(1, frames + 1):
            t0 = time.perf_counter_ns()
            platform_box.offer(Offer(gen, slot.name, SHAPE, gen, t0, t0, telemetry, 0.1))
            t1 = time.perf_counter_ns()
            runner._messages.poll(0)
            t2 = time.perf_counter_ns()
            offer = child_box.claim()
            t3 = time.perf_counter_ns()
            result = runner.process(offer)
            t4 = time.perf_counter_ns()
            send_message(child_end, result)
            t5 = time.perf_counter_ns()
            for data, buffers in inbox.read():
                decode_from_child(data, buffers)
            t6 = time.perf_counter_ns()
            for name, ns in zip(steps, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4, t6 - t5), strict=True):
                steps[name] += ns
    finally:
        inbox.close()
        child_box.close()
        for segment in (platform_box._shm, slot):
            resource_tracker.register(segment._name, "shared_memory")
        platform_box.close()
        slot.close()
        slot.unlink()
    per_frame = {f"{name}_us": round(ns / frames / 1000, 2) for name, ns in steps.items()}
    return {"frames": frames, **per_frame, "total_us": round(sum(steps.values()) / frames / 1000, 2)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20_000)
    print(json.dumps(measure(parser.parse_args().frames)))


if __name__ == "__main__":
    main()
