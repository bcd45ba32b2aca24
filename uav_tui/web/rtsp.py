"""The processed video as an RTSP stream (``video_rtsp_port``): GStreamer's RTSP server through PyGObject.

:class:`RtspServer` is a :class:`~uav_tui.web.ground_video.Target`: the platform's own encoder (PyAV, as for RTP)
makes the H.264; the server only packs it into RTP and serves it to each client that asks for
``rtsp://HOST:PORT/PATH`` (over TCP or UDP, as the client chooses). Its pipeline
is ``appsrc ! rtph264pay``, one for all clients (shared), made when the first client plays and dropped when the
last one leaves. The server runs its own GLib main loop in the ``rtsp-server`` thread; the encoding thread only
hands it finished frames, never waiting: with no client nothing is encoded, and a frame that finds the pipeline's
queue full goes to no one, counted by the :class:`GroundVideo`. A client slower than the stream over TCP loses
packets from the server's own backlog instead (gst-rtsp-server's ``drop-backlog``, its default; not measured
here): its picture is damaged until the next key frame, within a second. A client that
joins gets a key frame next. A connection that closes without a TEARDOWN (a receiver killed) ends its session
at once (0.1 s after the kill here, over TCP and UDP alike): the server stops sending to it.

Why GStreamer's server: FFmpeg's RTSP muxer is a client (ANNOUNCE / RECORD to a server); its ``listen`` flag is
its demuxer's only (the muxer still connects out: "Connection refused"). The RTSP server packages on PyPI are
young; gst-rtsp-server is GStreamer's own, maintained with it, in Debian's packages.
PyGObject comes from Debian (``python3-gi``): PyPI's builds from source only (a compiler, GLib's and cairo's
headers). ``scripts/setup.sh`` links it into the venv.
"""

from __future__ import annotations

import threading
import time
import warnings
from typing import Any

from uav_tui.errors import ConfigError
from uav_tui.web.ground_video import configure_encoder, stamp
from uav_tui.web.rtp import RTSP

QUEUE_FRAMES = 3
"""Frames the server's queue holds for its clients; a frame that finds it full goes to no one."""
PIPELINE = ("( appsrc name=src is-live=true format=time do-timestamp=true "
            "caps=video/x-h264,stream-format=byte-stream,alignment=au "
            "! rtph264pay name=pay0 pt=96 config-interval=-1 )")
"""The pipeline each stream's clients share: the encoded frames in, RTP out (the server's own payloader)."""
INSTALL = ("apt-get install python3-gi gir1.2-gst-rtsp-server-1.0 gstreamer1.0-plugins-good, then "
           "bash scripts/setup.sh")


def gstreamer() -> tuple[Any, Any, Any]:
    """(Gst, GstRtspServer, GLib), initialised; ConfigError saying what to install when they are missing."""
    try:
        import gi

        gi.require_version("Gst", "1.0")
        gi.require_version("GstRtspServer", "1.0")
        with warnings.catch_warnings():  # Debian's PyGObject 3.42 on Python 3.11's import system: harmless
            warnings.filterwarnings("ignore", "DynamicImporter.exec_module", ImportWarning)
            from gi.repository import GLib, Gst, GstRtspServer
    except (ImportError, ValueError) as exc:
        raise ConfigError(f"video_rtsp_port needs GStreamer's RTSP server through PyGObject ({exc}): {INSTALL}",
                          key="video_rtsp_port") from exc
    Gst.init(None)
    if Gst.ElementFactory.find("rtph264pay") is None or Gst.ElementFactory.find("appsrc") is None:
        raise ConfigError(f"video_rtsp_port needs GStreamer's appsrc and rtph264pay: {INSTALL}",
                          key="video_rtsp_port")
    return Gst, GstRtspServer, GLib


class RtspServer:
    """An RTSP server with one H.264 stream at ``rtsp://HOST:PORT/PATH``.

    Args:
        port: the TCP port it listens on (0: any free one; :attr:`port` then says which).
        path: the stream's path, from ``/``.
        host: the address it binds to.
    """

    kind = RTSP

    def __init__(self, port: int, path: str, host: str = "0.0.0.0") -> None:
        self.port, self.path, self.host = port, path, host
        self._gst, rtsp, glib = gstreamer()
        self._source: Any = None
        """The shared pipeline's appsrc while a client plays, else None."""
        self._joined = False
        """A client joined since the last frame: the next one is a key frame."""
        self._server = rtsp.RTSPServer()
        self._server.set_address(host)
        self._server.set_service(str(port))
        self._server.connect("client-connected", self._connected)
        factory = rtsp.RTSPMediaFactory()
        factory.set_launch(PIPELINE)
        factory.set_shared(True)
        factory.connect("media-configure", self._configure)
        self._server.get_mount_points().add_factory(path, factory)
        self._context = glib.MainContext.new()
        self._loop = glib.MainLoop.new(self._context, False)
        self._listening = self._server.attach(self._context)
        """The id of the server's listening socket's source in the context (0: it could not listen)."""
        if self._listening == 0:
            raise ConfigError(f"video_rtsp_port {port}: the RTSP server cannot listen on {host}:{port} (in use, "
                              "or below 1024 without the right)", key="video_rtsp_port")
        if port == 0:
            self.port = self._server.get_bound_port()
        self._thread = threading.Thread(target=self._loop.run, name="rtsp-server", daemon=True)
        self._thread.start()

    @property
    def uri(self) -> str:
        return f"rtsp://{self.host}:{self.port}{self.path}"

    @property
    def watched(self) -> bool:
        """A client plays the stream."""
        return self._source is not None

    def receiver_uri(self, host: str) -> str:
        return f"rtsp://{host}:{self.port}{self.path}"

    def open(self, encoder: str, width: int, height: int, fps: float, kbps: int) -> _RtspOutput:
        return _RtspOutput(self, encoder, width, height, fps, kbps)

    def push(self, data: bytes) -> bool:
        """Hand one encoded frame to the clients (any thread); False when none takes it (none, or a full queue)."""
        source = self._source
        if source is None or source.get_property("current-level-buffers") >= QUEUE_FRAMES:
            return False
        source.emit("push-buffer", self._gst.Buffer.new_wrapped(data))
        return True

    def take_joined(self) -> bool:
        """Whether a client joined since this was last asked (the next frame should be a key frame)."""
        joined, self._joined = self._joined, False
        return joined

    def close(self) -> None:
        """Stop serving: the clients' connections close, and the port is free again. Idempotent."""
        if self._thread.is_alive():
            self._context.invoke_full(0, self._quit)
            self._thread.join(timeout=2.0)

    def _quit(self) -> bool:
        for client in self._server.client_filter(None):
            client.close()
        self._context.find_source_by_id(self._listening).destroy()  # closes the listening socket
        self._loop.quit()
        return False

    # -- on the server's thread ------------------------------------------------------------------------

    def _configure(self, _factory: Any, media: Any) -> None:
        """The first client of a new shared pipeline: its appsrc takes the frames from now on."""
        source = media.get_element().get_by_name("src")
        media.connect("unprepared", self._unprepared, source)
        self._source = source
        self._joined = True

    def _unprepared(self, _media: Any, source: Any) -> None:
        if self._source is source:  # not a newer pipeline's, made before this one was undone
            self._source = None

    def _connected(self, _server: Any, client: Any) -> None:
        client.connect("play-request", self._playing)

    def _playing(self, _client: Any, _context: Any) -> None:
        self._joined = True  # a second client of the same pipeline needs a key frame too


class _RtspOutput:
    """One encoder feeding the RTSP server (PyAV, the same settings as RTP's)."""

    def __init__(self, server: RtspServer, encoder: str, width: int, height: int, fps: float, kbps: int) -> None:
        import av

        self._server = server
        self._codec: Any = av.CodecContext.create(encoder, "w")
        # One slice a frame: FFmpeg's RTSP client decoded the first of x264's two slices of each P-frame from this
        # server's payloader as grey (measured at 640x480); on one thread p95 stays at 106 ms, CPU the same.
        configure_encoder(self._codec, encoder, width, height, fps, kbps, one_slice=True)
        self._key = av.video.frame.PictureType.I
        self._started = time.monotonic()

    def send(self, frame: Any) -> bool:
        stamp(frame, self._started)
        if self._server.take_joined():
            frame.pict_type = self._key
        delivered = False
        for packet in self._codec.encode(frame):
            delivered = self._server.push(bytes(packet)) or delivered
        return delivered

    def close(self) -> None:
        """Nothing to flush: frames still in the encoder are of no use to a live stream."""
