"""The one wrapper for MAVSDK calls: bounded in time, and a call that never returns keeps nothing alive."""

from __future__ import annotations

import asyncio
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from controllers.errors import CommandDenied, LinkLost
from controllers.mavsdk.calls import bounded

ROOT = Path(__file__).resolve().parents[2]

STUCK_CALL = textwrap.dedent("""
    import asyncio, threading
    from controllers.mavsdk.calls import bounded, use_abandoning_executor

    async def main():
        executor = use_abandoning_executor()
        never = threading.Event()
        loop = asyncio.get_running_loop()
        try:
            await bounded("hold", lambda: loop.run_in_executor(None, never.wait), 0.2)
        except Exception as exc:
            print(type(exc).__name__, exc)
        print("still blocked:", executor.running)

    asyncio.run(main())
    print("exiting")
""")


def test_a_call_that_never_returns_is_abandoned_and_the_process_exits() -> None:
    done = subprocess.run([sys.executable, "-c", STUCK_CALL], cwd=ROOT, capture_output=True, text=True, timeout=30)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("CommandDenied hold refused by the autopilot (TIMEOUT)")
    assert lines[1] == "still blocked: ['Event.wait']"
    assert lines[2] == "exiting"


@pytest.mark.parametrize(("heartbeat_age", "error"), [(0.1, CommandDenied), (5.0, LinkLost)])
async def test_timeout_is_translated_by_link_state(heartbeat_age: float, error: type) -> None:
    never = asyncio.Event()
    with pytest.raises(error, match="hold"):
        await bounded("hold", never.wait, 0.05, lambda: heartbeat_age)
