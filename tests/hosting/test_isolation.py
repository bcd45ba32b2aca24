"""Process isolation: nothing the processor does can freeze or kill the platform.

Every flight goes through a real UavCore, real MAVSDK and the simulator process; whether the vehicle
held comes from the simulator's ground truth.
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import json
import os
import select
import subprocess
import sys
import threading
import time
from collections import Counter
from pathlib import Path

import pytest

from tests.core.flight_helpers import fly_under_autonomy, flying_core, speed, wait_until
from tests.videos import create_video_file
from uav_tui.config import load_config
from uav_tui.core import UavCore
from uav_tui.errors import ConfigError, ProcessorLoadError, UavError
from uav_tui.events import EventLog
from uav_tui.headless import format_status
from uav_tui.hosting import frame_feeder
from uav_tui.hosting.host import HostState
from uav_tui.hosting.process_host import SubprocessHost
from uav_tui.recorded import dataset

MAX_T = 1.5

FAULTY = '''
import ctypes, os, time
from pathlib import Path

class Faulty:
    """F1 flies forward and saves every frame, F2 dies as ``crash`` says, F3 holds the GIL, F4 hangs."""

    def __init__(self, crash="exit", marker="", speed=0.6):
        if marker and Path(marker + ".broken").exists():
            raise RuntimeError("constructor fails while the marker exists")
        self.tmMgr = None
        self.crash, self.marker, self.speed = crash, marker, speed
        self.mode = "idle"
        self.frames = 0

    def photo_processing(self, frame):
        self.frames += 1
        if self.mode == "fly":
            self.tmMgr.save(frame, n=self.frames, alt=self.tmMgr.snapshot().rel_alt_m, alive=self.tmMgr.link_alive())
        elif self.mode == "hog":
            sum(range(10**10))  # pure Python: holds the GIL for minutes
        elif self.mode == "crash":
            Path(self.marker).write_text(str(time.monotonic_ns()))
            if self.crash == "init":
                Path(self.marker + ".broken").touch()
            if self.crash in ("exit", "init"):
                os._exit(3)
            if self.crash == "segfault":
                ctypes.string_at(0)
            blocks = []
            while True:
                blocks.append(bytearray(50 * 2**20))

    def customize_processing(self, id):
        if id == 4:
            time.sleep(60)
        self.mode = {1: "fly", 2: "crash", 3: "hog"}[id]

    def getPreparedVector(self):
        return (self.speed, 0.0, 2.0) if self.mode == "fly" else None
'''

CHILD_MODULES = ["uav_tui", "uav_tui.hosting", "uav_tui.hosting.codec", "uav_tui.hosting.frame_call",
                 "uav_tui.hosting.frame_mailbox", "uav_tui.hosting.pipe", "uav_tui.hosting.tracks",
                 "uav_tui.hosting.wire"]
"""The platform's modules the processor's process imports beside its main loop (``__main__``, from
``uav_tui.hosting.child``): what it shares with the platform."""
MODULES = '''
import sys

class Modules:
    def photo_processing(self, frame):
        pass

    def customize_processing(self, id):
        return sorted(sys.modules)
'''


def faulty(tmp_path: Path) -> str:
    path = tmp_path / "faulty.py"
    path.write_text(FAULTY)
    return f"{path}:Faulty"


def messages(core: UavCore, kind: str) -> list[str]:
    return [e.message for e in core.events.recent if e.kind == kind]


def restarted(core: UavCore, old_pid: int | None) -> bool:
    """A processor other than ``old_pid``'s is running."""
    state = core.worker.state()
    return state.phase.state is HostState.RUNNING and state.pid != old_pid


def held(core: UavCore) -> bool:
    truth = core.truth.latest()
    return truth["mode"] == "HOLD" and speed(truth) < 0.15


async def test_the_processor_process_loads_no_platform_module(tmp_path: Path) -> None:
    (tmp_path / "modules.py").write_text(MODULES)
    worker = await SubprocessHost.start(f"{tmp_path}/modules.py:Modules", {}, print, events=EventLog(),
                                       on_fault=print)
    try:
        loaded = (await worker.call("customize_processing", 1)).value
    finally:
        worker.close()
    assert "processors.loading" in loaded and "numpy" in loaded  # it is the processor's process ...
    platform = [name for name in loaded if name.split(".")[0] in ("uav_tui", "sources", "controllers")]
    assert platform == CHILD_MODULES  # ... and of the platform only its own few modules came in
    assert not {"asyncio", "textual", "mavsdk", "aiohttp"} & set(loaded)


@pytest.mark.serial  # bounds the event loop's lag: a busy neighbour on the other core breaks it
async def test_a_gil_hog_cannot_freeze_the_platform(tmp_path: Path) -> None:
    async with flying_core(tmp_path, processor=faulty(tmp_path), max_t=MAX_T, processor_timeout=4.0, record=True,
                           runs_dir=str(tmp_path / "runs")) as core:
        await fly_under_autonomy(core, lambda: speed(core.truth.latest()) > 0.4, "flying the vectors")
        lags: list[float] = []

        async def measure_lag() -> None:
            while True:
                before = time.monotonic()
                await asyncio.sleep(0.02)
                lags.append(time.monotonic() - before - 0.02)

        ticker = asyncio.create_task(measure_lag())
        old_pid = core.worker.state().pid
        await core.execute("f 3")
        await wait_until(lambda: core.worker.busy_s > 0.3, 5, "the processor to hog the GIL")
        hog_started = time.monotonic() - core.worker.busy_s
        updates = core.telemetry.updates
        assert "saved" in await core.execute("snapshot", origin="tui")  # the platform answers meanwhile
        await wait_until(lambda: not core.gate.enabled, MAX_T + 2, "the watchdog to stop autonomy")
        stopped_after = time.monotonic() - hog_started
        assert "processor stalled" in core.status().autonomy_stop_reason
        assert stopped_after <= MAX_T + 0.5 + 0.05  # + this test's polling period
        await wait_until(lambda: held(core), 5, "zero and hold")
        assert core.telemetry.updates > updates + 10  # telemetry kept flowing
        ticker.cancel()
        assert max(lags) < 0.1, f"event loop lag up to {max(lags) * 1000:.0f} ms"
        # processor_timeout: the child is killed and a fresh one started
        await wait_until(lambda: any("processor_timeout = 4 s" in m for m in messages(core, "processor")), 6,
                         "the hung process to be killed")
        await wait_until(lambda: restarted(core, old_pid), 10, "a fresh processor")
        assert any("select the target again" in m for m in messages(core, "processor"))


@pytest.mark.parametrize(("crash", "cause"), [
    ("exit", "exited with code 3"),
    ("segfault", "killed by SIGSEGV"),
    ("memory", "ran out of memory: processor_memory_mb = 400 MB reached"),
])
async def test_a_dying_processor_is_reported_the_vehicle_holds_and_it_restarts(
        tmp_path: Path, crash: str, cause: str) -> None:
    marker = tmp_path / "died"
    async with flying_core(tmp_path, processor=faulty(tmp_path), processor_args={"crash": crash, "marker": str(marker)},
                           processor_memory_mb=400, record=True, runs_dir=str(tmp_path / "runs")) as core:
        await fly_under_autonomy(core, lambda: speed(core.truth.latest()) > 0.4, "flying the vectors")
        old_pid = core.worker.state().pid
        frames_before = core.recorder.frames
        await core.execute("f 2")
        await wait_until(lambda: not core.gate.enabled, 5, "autonomy to stop")
        off = next(e for e in reversed(core.events.recent) if "autonomy OFF" in e.message)
        assert cause in off.message
        if crash != "memory":  # the marker is written the moment before it dies (filling memory takes a while)
            assert (off.t_mono_ns - int(marker.read_text())) / 1e9 < 0.2
        await wait_until(lambda: held(core), 5, "zero and hold")
        await wait_until(lambda: any(cause in m for m in messages(core, "processor")), 3, "the crash report")
        report = next(m for m in messages(core, "processor") if cause in m)
        assert {"segfault": "Segmentation fault", "memory": "MemoryError", "exit": ""}[crash] in report
        assert crash == "exit" or "faulty.py" in report  # where in the researcher's code it died
        await wait_until(lambda: restarted(core, old_pid), 10, "the restart")
        run_dir = core.recorder.run_dir
    frames = dataset.load(run_dir).frames
    kept = frames[frames.frame_id <= frames_before]
    assert sorted(kept.frame_id) == list(range(1, frames_before + 1))  # every row from before the fault
    flown = frames[frames.n.notna()]
    assert len(flown) > 5 and (flown.alt - 3.0).abs().max() < 0.6  # tmMgr.snapshot(): the frame's telemetry
    assert flown.alive.astype(bool).all()  # and the heartbeat's age at the hand-over


async def test_a_constructor_that_fails_on_restart_is_reported_and_retried(tmp_path: Path) -> None:
    marker = tmp_path / "died"
    async with flying_core(tmp_path, processor=faulty(tmp_path), processor_args={"crash": "init",
                                                                                  "marker": str(marker)}) as core:
        await fly_under_autonomy(core, lambda: speed(core.truth.latest()) > 0.4, "flying the vectors")
        old_pid = core.worker.state().pid
        await core.execute("f 2")
        await wait_until(lambda: held(core), 5, "zero and hold")
        assert "exited with code 3" in core.status().autonomy_stop_reason
        await wait_until(lambda: any("restart 1 failed" in m for m in messages(core, "processor")), 30,
                         "the first restart to fail")  # a new interpreter starting: seconds on a busy machine
        failure = next(m for m in messages(core, "processor") if "restart 1 failed" in m)
        assert "raised while constructing" in failure and "constructor fails while the marker exists" in failure
        assert core.status().processor_state.phase.state is HostState.RESTARTING
        Path(f"{marker}.broken").unlink()  # the researcher fixed it: the next attempt (after 2 s) loads
        await wait_until(lambda: restarted(core, old_pid), 30, "the second restart")


async def test_a_hung_call_times_out_and_never_blocks_other_commands(tmp_path: Path) -> None:
    async with flying_core(tmp_path, processor=faulty(tmp_path)) as core:
        started = time.monotonic()
        with pytest.raises(UavError, match=r"customize_processing\(4,\) did not return within 1 s"):
            await core.execute("f 4")
        assert time.monotonic() - started < 2.5
        with pytest.raises(UavError, match=r"has not returned from \S*customize_processing\(4,\)"):
            await asyncio.wait_for(core.execute("f 1"), 0.5)  # fails at once, does not queue behind it
        assert await asyncio.wait_for(core.execute("vector 0.5 0 3"), 1.0)
        await wait_until(lambda: speed(core.truth.latest()) > 0.3, 5, "the vector")
        assert await asyncio.wait_for(core.execute("hold"), 1.0) == "holding"
        await wait_until(lambda: held(core), 5, "hold")


@pytest.mark.serial  # a bound in real time
def test_sigterm_leaves_within_3_s_whatever_the_processor_does(tmp_path: Path) -> None:
    (tmp_path / "stuck.py").write_text(
        "import signal, time\n\nclass Stuck:\n    def photo_processing(self, frame):\n"
        "        signal.signal(signal.SIGTERM, signal.SIG_IGN)\n        time.sleep(600)\n")
    command = [sys.executable, "-m", "uav_tui", "--no-ui", "--json", "--no-record", "--fc", "none",
               "--source", "synthetic:?width=160&height=120", "--processor", f"{tmp_path}/stuck.py:Stuck"]
    with subprocess.Popen(command, stdout=subprocess.PIPE, text=True, cwd=tmp_path) as proc:
        try:
            status, deadline = None, time.monotonic() + 30
            while status is None or status["pipeline"]["busy_ms"] < 500:
                assert time.monotonic() < deadline, "no status line with a busy processor"
                if select.select([proc.stdout], [], [], 1.0)[0]:
                    line = json.loads(proc.stdout.readline())
                    status = line if "pipeline" in line else status
            child = status["processor_state"]["pid"]
            assert status["processor_state"]["isolation"] == "process" and child != proc.pid
            assert status["processor_state"]["state"] == "running"  # the text the web page shows
            sent = time.monotonic()
            proc.terminate()
            assert proc.wait(3.0) == 0 and time.monotonic() - sent < 3.0
            with pytest.raises(ProcessLookupError):
                os.kill(child, 0)  # the processor's process is gone too
        finally:
            proc.kill()


async def test_reload_swaps_only_a_processor_that_loads(tmp_path: Path) -> None:
    path = tmp_path / "versioned.py"
    version = ("class Versioned:\n    def photo_processing(self, frame):\n        pass\n\n"
               "    def getPreparedVector(self):\n        return ({v}, 0.0, 1.0)\n")
    path.write_text(version.format(v=0.1))
    core = UavCore(load_config(None, {"source": "synthetic:?width=160&height=120", "processor": f"{path}:Versioned",
                                      "fc": "none", "record": False}))
    await core.start()
    try:
        await wait_until(lambda: core.worker.last is not None, 10, "a frame")
        pid = core.worker.state().pid
        assert f"processor running, pid {pid}, " in format_status(core.status(), 1.0)  # and its memory
        path.write_text("class Versioned:\n    def photo_processing(self, frame)\n")
        with pytest.raises(ProcessorLoadError, match="reload failed, .* keeps running: .*SyntaxError"):
            await core.execute("reload")
        assert core.worker.state().pid == pid and core.worker.last.outcome.vector == (0.1, 0.0, 1.0)
        path.write_text(version.format(v=0.2))
        assert "reloaded" in await core.execute("reload")
        assert core.worker.state().pid != pid
        await wait_until(lambda: core.worker.last.outcome.vector == (0.2, 0.0, 1.0), 5, "the new code's vector")
    finally:
        await core.stop()



def open_descriptors(*, collect_garbage: bool = True) -> list[str]:
    """What this process has open, by default after collecting garbage (closing what only a reference cycle kept)."""
    if collect_garbage:
        gc.collect()
    targets = []
    for fd in os.listdir("/proc/self/fd"):
        with contextlib.suppress(OSError):  # the listing's own descriptor, closed by now
            targets.append(os.readlink(f"/proc/self/fd/{fd}"))
    return sorted(targets)


def left_open(before: list[str]) -> list[str]:
    """What is open now and was not in ``before`` (a multiset: a second descriptor of one file counts). Not an
    equality: what ``before``'s run still held may close later (under load a stopped run's last frame slot was
    still open right after its stop, and gone after the next run)."""
    return sorted((Counter(open_descriptors()) - Counter(before)).elements())


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="counts descriptors in Linux's /proc")
async def test_starting_stopping_and_reloading_leave_no_descriptor_open(tmp_path: Path) -> None:
    """Each child has a pipe, a mailbox and frame slots; none may outlive it (they ran out after ~200 starts).

    Both ways frames reach the slots: a video decoded into them, generated frames copied in.
    """
    video = tmp_path / "clip.mp4"
    create_video_file(video, frames=60)
    sources = [f"file:{video}?realtime=0", "synthetic:?width=160&height=120"]

    async def run_once(source: str, reloads: int = 0) -> None:
        core = UavCore(load_config(None, {"source": source, "processor": "template", "fc": "none", "record": False}))
        await core.start()
        try:
            await wait_until(lambda: core.worker.last is not None, 10, "a processed frame")
            for _ in range(reloads):
                assert "reloaded" in await core.execute("reload")
                await wait_until(lambda: core.worker.last is not None, 10, "a frame from the new child")
        finally:
            await core.stop()

    await run_once(sources[1])  # starts what lives as long as the process (the resource tracker)
    before = open_descriptors()
    for source in sources * 2:
        await run_once(source)
    assert left_open(before) == []
    sockets = [target for target in before if target.startswith("socket:")]
    gc.disable()  # the pipes are closed as their child ends, not whenever garbage is collected
    try:
        await run_once(sources[0], reloads=3)
        assert [t for t in open_descriptors(collect_garbage=False) if t.startswith("socket:")] == sockets
    finally:
        gc.enable()
    assert left_open(before) == []


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="counts descriptors in Linux's /proc")
async def test_a_frame_being_offered_at_stop_leaves_no_slot_open(monkeypatch: pytest.MonkeyPatch) -> None:
    """The feeder thread may be offering a frame it copied into a slot as the platform stops: stop waits for it."""
    config = load_config(None, {"source": "synthetic:?width=160&height=120", "processor": "template", "fc": "none",
                                "record": False})

    async def run_once(*, stop_while_offering: bool) -> None:
        core = UavCore(config)
        await core.start()
        await wait_until(lambda: core.worker.last is not None, 10, "a processed frame")
        if stop_while_offering:
            offering = threading.Event()
            telemetry_at = frame_feeder.FrameFeeder._telemetry_at

            def slowly(feeder: frame_feeder.FrameFeeder, t_mono_ns: int) -> tuple[bytes, float | None]:
                offering.set()  # the frame is in its slot, not offered yet
                time.sleep(0.5)
                return telemetry_at(feeder, t_mono_ns)

            monkeypatch.setattr(frame_feeder.FrameFeeder, "_telemetry_at", slowly)
            await asyncio.get_running_loop().run_in_executor(None, offering.wait, 5)
        await core.stop()

    await run_once(stop_while_offering=False)  # starts what lives as long as the process (the resource tracker)
    before = open_descriptors()
    await run_once(stop_while_offering=True)
    assert left_open(before) == []


def test_isolation_accepts_only_process_or_thread() -> None:
    assert load_config(None, {"isolation": "thread"}).isolation == "thread"
    with pytest.raises(ConfigError, match="isolation must be one of process, thread, got 'procss'"):
        load_config(None, {"isolation": "procss"})
