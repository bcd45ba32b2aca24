"""aioice's mDNS resolver, made to belong to the event loop that serves the page.

Chromium hides a viewer's addresses behind ``*.local`` names in its ICE candidates. aioice resolves
them with one mDNS socket per *thread*, guarded by one ``asyncio.Lock`` that it creates once and never
replaces; the lock binds to the first event loop on which two names are resolved at once. A core
started on a later event loop of the same thread (a script or a test suite calling ``asyncio.run``
again) then had every such offer refused with "Lock ... is bound to a different event loop": the page
loaded, the viewer never got video.
"""

from __future__ import annotations

import asyncio
import weakref

from aioice import ice

_adopted: weakref.WeakSet[asyncio.AbstractEventLoop] = weakref.WeakSet()


def adopt_mdns_resolver() -> None:
    """Make aioice's per-thread mDNS state the running loop's; call it on the loop that serves offers.

    The first call on a loop drops what an earlier loop of this thread left (that loop no longer runs,
    so nothing of it can still resolve); aioice creates a new lock and socket on this loop when a
    viewer's candidates need them. Later calls on the same loop change nothing.
    """
    loop = asyncio.get_running_loop()
    if loop in _adopted:
        return
    _adopted.add(loop)
    state = ice._mdns  # aioice has no public way to reset it
    for name in ("lock", "protocol", "subscribers"):
        if hasattr(state, name):
            delattr(state, name)
