"""The ground-station video: latency to a decoding receiver, the CPU it adds, FPS with it on vs off.

The platform runs a 30 FPS synthetic camera at 640x480 through a processor that draws each frame's capture number
into it as 24 black or white blocks (its overlay: what the ground station sees); the stream goes at 30 FPS and
1.5 Mbit/s (``libx264``) to FFmpeg's command-line tool on loopback, which decodes it to raw frames: over RTP/UDP
(``video_out``), or with ``--rtsp`` from the RTSP server (``video_rtsp_port``, played over TCP as QGC does). Each
decoded frame's number is read back from the blocks: capture (the frame's own stamp) to decoded at the receiver,
p50/p95. CPU: the platform's process (and the processor's) over the same seconds with the stream on and off, as a
share of one core; processed FPS on / off. Needs ``ffmpeg`` (Debian's). Prints one JSON object.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import psutil

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from uav_tui.config import load_config  # noqa: E402
from uav_tui.core import UavCore  # noqa: E402
from uav_tui.relays.contract import HandledFrame  # noqa: E402
from uav_tui.web.rtp import Destination  # noqa: E402

WIDTH, HEIGHT, FPS, KBPS = 640, 480, 30, 1500
BITS = 24
BLOCK = WIDTH // BITS
GOALS = {"latency_p95_ms": 150.0, "extra_core_share": 0.15, "fps_ratio": 0.97}


NUMBERED = f"""
class Numbered:
    \"\"\"Draws the frame's capture number (tmMgr.snapshot().frame_seq) as {BITS} blocks along the top.\"\"\"

    def __init__(self):
        self.tmMgr = None

    def photo_processing(self, frame):
        seq = self.tmMgr.snapshot().frame_seq
        for bit in range({BITS}):
            frame[:{BLOCK}, bit * {BLOCK}:(bit + 1) * {BLOCK}] = 255 if seq >> bit & 1 else 0
"""
"""The processor, written into the run's folder: it runs in its own process and loads by file."""


def read_number(frame: np.ndarray) -> int:
    means = frame[4:BLOCK - 4, :BITS * BLOCK].reshape(BLOCK - 8, BITS, BLOCK, 3)[:, :, 4:BLOCK - 4].mean(axis=(0, 2, 3))
    return sum(1 << bit for bit in range(BITS) if means[bit] > 128)


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def receiver(source: list[str], decoded: dict[int, int], stop: threading.Event) -> subprocess.Popen[bytes]:
    """FFmpeg decoding the stream from ``source`` (its input options); a thread stamps each decoded frame's number
    at its arrival here."""
    process = subprocess.Popen(["ffmpeg", "-hide_banner", "-loglevel", "error", "-fflags", "nobuffer", "-flags",
                                "low_delay", "-reorder_queue_size", "0", *source, "-f", "rawvideo", "-pix_fmt",
                                "bgr24", "-"], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                               stderr=subprocess.DEVNULL)

    def read() -> None:
        size = WIDTH * HEIGHT * 3
        assert process.stdout is not None
        while not stop.is_set() and len(data := process.stdout.read(size)) == size:
            decoded.setdefault(read_number(np.frombuffer(data, np.uint8).reshape(HEIGHT, WIDTH, 3)),
                               time.monotonic_ns())

    threading.Thread(target=read, name="bench-receiver", daemon=True).start()
    return process


def free_tcp_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


async def run(seconds: float, stream: bool, rtsp: bool, folder: Path) -> dict[str, Any]:
    port = free_tcp_port() if rtsp else free_udp_port()
    settings: dict[str, Any] = {"source": f"synthetic:?width={WIDTH}&height={HEIGHT}&fps={FPS}", "fc": "none",
                                "processor": f"{folder / 'numbered.py'}:Numbered", "record": False}
    if stream:
        settings |= {"video_rtsp_port": port} if rtsp else {"video_out": f"rtp://127.0.0.1:{port}"}
        settings |= {"video_out_width": WIDTH, "video_out_fps": FPS, "video_out_kbps": KBPS}
    captured: dict[int, int] = {}
    decoded: dict[int, int] = {}
    stop = threading.Event()
    listening = None
    if stream and not rtsp:  # RTP: listening before the first packet
        sdp = folder / "stream.sdp"
        sdp.write_text(Destination("127.0.0.1", port).sdp())
        listening = receiver(["-protocol_whitelist", "file,udp,rtp", "-i", str(sdp)], decoded, stop)
    core = UavCore(load_config(None, settings))
    await core.start()
    if stream and rtsp:  # RTSP: the client connects to the platform's server
        listening = receiver(["-rtsp_transport", "tcp", "-i", f"rtsp://127.0.0.1:{port}/video"], decoded, stop)

    def seen(result: HandledFrame) -> None:
        captured[result.frame.seq] = result.frame.t_mono_ns

    core.add_frame_listener(seen)
    try:
        await asyncio.sleep(3.0)  # warm: the encoder's first key frame, the receiver's start
        me = psutil.Process()
        child = psutil.Process(core.worker.state().pid) if core.worker and core.worker.state().pid else None
        cpu0 = sum(sum(p.cpu_times()[:2]) for p in (me, child) if p)
        first, wall0 = max(captured, default=0), time.monotonic()
        await asyncio.sleep(seconds)
        wall = time.monotonic() - wall0
        cpu = sum(sum(p.cpu_times()[:2]) for p in (me, child) if p) - cpu0
        last = max(captured, default=0)
        sending = core.side_channels.rtsp if rtsp else core.side_channels.video
        video = sending.status() if sending else None
    finally:
        await core.stop("benchmark done")
        stop.set()
        if listening is not None:
            listening.kill()
            listening.wait()
    measured = [decoded[seq] - captured[seq] for seq in range(first + 1, last + 1)
                if seq in decoded and seq in captured]
    result: dict[str, Any] = {"processed_fps": round((last - first) / wall, 2), "core_share": round(cpu / wall, 3)}
    if stream:
        ms = np.array(measured) / 1e6
        result |= {"decoded_frames": len(measured), "video": video,
                   "latency_ms": {"p50": round(float(np.percentile(ms, 50)), 1),
                                  "p95": round(float(np.percentile(ms, 95)), 1),
                                  "max": round(float(ms.max()), 1)} if len(ms) else None}
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--rtsp", action="store_true", help="the RTSP stream (video_rtsp_port), not RTP/UDP")
    args = parser.parse_args()
    if shutil.which("ffmpeg") is None:
        parser.error("needs Debian's ffmpeg as the receiver: apt-get install ffmpeg")
    with tempfile.TemporaryDirectory() as folder:
        (Path(folder) / "numbered.py").write_text(NUMBERED)
        off = asyncio.run(run(args.seconds, False, args.rtsp, Path(folder)))
        on = asyncio.run(run(args.seconds, True, args.rtsp, Path(folder)))
    latency = on["latency_ms"]["p95"] if on.get("latency_ms") else None
    extra = round(on["core_share"] - off["core_share"], 3)
    ratio = round(on["processed_fps"] / off["processed_fps"], 3)
    print(json.dumps({
        "benchmark": "video_out_rtsp" if args.rtsp else "video_out",
        "transport": "RTSP, played over TCP" if args.rtsp else "RTP/UDP", "size": f"{WIDTH}x{HEIGHT}",
        "fps": FPS, "kbps": KBPS, "cpus": os.cpu_count(),
        "load_average_1min_at_end": round(os.getloadavg()[0], 2), "off": off, "on": on,
        "goals": {"capture to decoded p95 (ms)": {"goal": f"<= {GOALS['latency_p95_ms']:g}", "value": latency,
                                                  "pass": latency is not None and latency <= GOALS["latency_p95_ms"]},
                  "CPU the stream adds (share of a core)": {"goal": f"<= {GOALS['extra_core_share']:g}",
                                                            "value": extra,
                                                            "pass": extra <= GOALS["extra_core_share"]},
                  "processed FPS on / off": {"goal": f">= {GOALS['fps_ratio']:g}", "value": ratio,
                                             "pass": ratio >= GOALS["fps_ratio"]}}}, indent=1))


if __name__ == "__main__":
    main()
