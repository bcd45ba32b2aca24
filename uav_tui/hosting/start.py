"""Starting the processor's host where ``isolation`` says, and saying so while the processor loads."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable

from processors.base import ProcessorInfo
from uav_tui.config import Config, Isolation
from uav_tui.events import EventLog
from uav_tui.hosting.host import ProcessedFrame, ProcessorHost
from uav_tui.hosting.process_host import SubprocessHost
from uav_tui.hosting.supervisor import LOAD_TIMEOUT_S
from uav_tui.hosting.thread_host import ThreadHost, load_in_thread

LOADING_NOTICE_S = 5.0
"""How often a processor still loading is said to be (``loading processor X ... (10 s)``)."""


async def start_host(config: Config, on_result: Callable[[ProcessedFrame], None], events: EventLog,
                     on_fault: Callable[[str], None]) -> ProcessorHost:
    """Load the processor in its own process (default) or a thread of this one; said every
    :data:`LOADING_NOTICE_S` while it loads (a slow ``__init__`` is not silence)."""
    notices = asyncio.create_task(_say_loading(config, events), name="loading notices")
    host: ProcessorHost
    try:
        if config.isolation == Isolation.THREAD:
            processor = await load_in_thread(config.processor, config.processor_args)
            host = ThreadHost(processor, on_result, save_max_hz=config.recording.save_max_hz, events=events)
        else:
            host = await SubprocessHost.start(
                config.processor, config.processor_args, on_result, events=events, on_fault=on_fault,
                timeout_s=config.processor_timeout, memory_mb=config.processor_memory_mb or None,
                save_images=config.recording.record, save_max_hz=config.recording.save_max_hz)
    finally:
        notices.cancel()
    say_load_warnings(host.processor.info, events)
    return host


def say_load_warnings(info: ProcessorInfo, events: EventLog) -> None:
    """What looks wrong in the processor just loaded (a misspelt method name), as warnings."""
    for warning in info.warnings:
        events.emit("warning", "processor", warning)


async def _say_loading(config: Config, events: EventLog) -> None:
    started = time.monotonic()
    limit = f"; given up at {LOAD_TIMEOUT_S:g} s" if config.isolation == Isolation.PROCESS else ""
    while True:
        await asyncio.sleep(LOADING_NOTICE_S)
        events.emit("info", "processor", f"loading processor {config.processor} ... "
                    f"({time.monotonic() - started:.0f} s{limit})")
