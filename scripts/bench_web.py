"""Benchmark of the web page: added latency from capture to the browser, and the CPU cost of streaming.

Runs a core in-process (synthetic camera, template processor, ``--fc none``, web page on loopback at
the default stream settings) and watches it with Debian's headless Chromium driven by Playwright.
Every processed frame gets its capture sequence number drawn as two rows of black/white blocks in
its top-left corner (the second row inverted, as a check); the page draws each presented video
frame into a canvas (requestVideoFrameCallback), reads the blocks back and records when the frame
was presented. Both clocks are this machine's wall clock. CPU is this process's CPU time (capture,
processing, conversion, encoding, signalling; the browser not included) over wall time.

Usage: python scripts/bench_web.py [--seconds 8] [--source synthetic:]   -> JSON on stdout
"""

from __future__ import annotations

import argparse
import asyncio
import json
import socket
import statistics
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from controllers.sim.launcher import free_ports  # noqa: E402
from uav_tui.config import load_config  # noqa: E402
from uav_tui.core import UavCore  # noqa: E402
from uav_tui.relays.contract import HandledFrame  # noqa: E402

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
BITS, BLOCK = 16, 16
"""The stamp: BITS blocks of BLOCK x BLOCK pixels per row, two rows."""

READER_JS = """([bits, block, frameWidth]) => {
  const video = document.getElementById('video');
  const scale = video.videoWidth / frameWidth;  // the stream may be scaled down from the frame
  const canvas = document.createElement('canvas');
  canvas.width = Math.ceil(bits * block * scale); canvas.height = Math.ceil(2 * block * scale);
  const ctx = canvas.getContext('2d', { willReadFrequently: true });
  window.__stamps = [];
  const read = (row, i) => {
    const px = ctx.getImageData((i + 0.5) * block * scale, (row + 0.5) * block * scale, 1, 1).data;
    return (px[0] + px[1] + px[2]) / 3 > 128 ? 1 : 0;
  };
  const onFrame = (now, meta) => {
    const shown = performance.timeOrigin + meta.expectedDisplayTime;
    ctx.drawImage(video, 0, 0, canvas.width, canvas.height, 0, 0, canvas.width, canvas.height);
    let seq = 0, valid = true;
    for (let i = 0; i < bits; i++) {
      const bit = read(0, i);
      if (read(1, i) === bit) valid = false;
      seq = seq * 2 + bit;
    }
    if (valid) window.__stamps.push([seq, shown]);
    video.requestVideoFrameCallback(onFrame);
  };
  video.requestVideoFrameCallback(onFrame);
}"""


def stamp(image: Any, seq: int) -> None:
    """Draw ``seq`` (16 bits, MSB first) and its complement as blocks into the image's corner."""
    for i in range(BITS):
        bit = (seq >> (BITS - 1 - i)) & 1
        x = i * BLOCK
        image[0:BLOCK, x:x + BLOCK] = 255 * bit
        image[BLOCK:2 * BLOCK, x:x + BLOCK] = 255 * (1 - bit)


def percentiles(values: list[float]) -> dict[str, float]:
    if not values:
        return {"n": 0}
    ordered = sorted(values)
    return {"n": len(ordered), "p50": round(statistics.median(ordered), 1),
            "p95": round(ordered[min(len(ordered) - 1, int(0.95 * len(ordered)))], 1),
            "min": round(ordered[0], 1), "max": round(ordered[-1], 1)}


async def cpu_percent(seconds: float) -> float:
    cpu, wall = time.process_time(), time.monotonic()
    await asyncio.sleep(seconds)
    return round(100 * (time.process_time() - cpu) / (time.monotonic() - wall), 1)


async def bench(seconds: float, source: str) -> dict[str, Any]:
    from playwright.async_api import async_playwright

    (port,) = free_ports(1, socket.SOCK_STREAM)
    core = UavCore(load_config(None, {"source": source, "fc": "none", "record": False, "web": True,
                                      "web_host": "127.0.0.1", "web_port": port}))
    frames: dict[int, tuple[int, int]] = {}

    def on_frame(result: HandledFrame) -> None:  # runs before the web track takes the frame
        seq = result.frame.seq & 0xFFFF
        stamp(result.frame.image, seq)
        frames[seq] = (result.frame.t_wall_ns, time.time_ns())

    core.add_frame_listener(on_frame)
    await core.start()
    try:
        await asyncio.sleep(1.0)
        cpu = {"no_viewer": await cpu_percent(min(seconds, 5))}
        async with async_playwright() as pw:
            browser = await pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            pages = []
            for _ in range(2):
                page = await browser.new_page(viewport={"width": 1000, "height": 700})
                await page.goto(core.web.url)
                await page.wait_for_function(
                    "document.getElementById('video').getVideoPlaybackQuality().totalVideoFrames > 5", timeout=20000)
                pages.append(page)
                if len(pages) == 1:
                    await asyncio.sleep(2.0)  # warm-up: encoder ramp-up, jitter buffer
                    await page.evaluate(READER_JS, [BITS, BLOCK, core.source.get_frame_size()[0]])
                    cpu["one_viewer"] = await cpu_percent(seconds)
                    stamps = await page.evaluate("window.__stamps")
                    shown = await page.evaluate(
                        "document.getElementById('video').getVideoPlaybackQuality().totalVideoFrames")
            await asyncio.sleep(1.0)
            cpu["two_viewers"] = await cpu_percent(min(seconds, 5))
            await browser.close()
    finally:
        await core.stop("benchmark finished")
    capture, processed = [], []
    for seq, shown_ms in stamps:
        if seq in frames:
            t_capture, t_processed = frames[seq]
            capture.append(shown_ms - t_capture / 1e6)
            processed.append(shown_ms - t_processed / 1e6)
    web = core.config.web
    return {
        "benchmark": "web",
        "settings": {"source": source, "processor": core.config.processor, "web_width": web.web_width,
                     "web_fps": web.web_fps, "seconds": seconds},
        "latency_ms": {"capture_to_display": percentiles(capture), "processed_to_display": percentiles(processed)},
        "frames_read_in_page": len(stamps),
        "displayed_fps": round(len(stamps) / seconds, 1),
        "total_video_frames": shown,
        "cpu_percent_of_one_core": {**cpu, "added_by_one_viewer": round(cpu["one_viewer"] - cpu["no_viewer"], 1),
                                    "added_by_second_viewer": round(cpu["two_viewers"] - cpu["one_viewer"], 1)},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=8.0, help="measuring window with one viewer")
    parser.add_argument("--source", default="synthetic:", help="camera URI (default: synthetic:, 640x480 @ 30 fps)")
    args = parser.parse_args()
    print(json.dumps(asyncio.run(bench(args.seconds, args.source)), indent=2))


if __name__ == "__main__":
    main()
