"""Real network stream servers on loopback for the network-source tests and the benchmark.

``RtspTestServer`` is a small RTSP server (RFC 2326): OPTIONS, DESCRIBE, SETUP, PLAY, TEARDOWN,
GET_PARAMETER, sending H.264 (libx264 through PyAV) as RTP (RFC 6184, single NAL units and FU-A)
interleaved in the RTSP TCP connection. ``MjpegTestServer`` serves multipart JPEG over HTTP the way
IP cameras and ``mjpg-streamer`` do. Both render a moving synthetic scene and can be stopped and
started again on the same port, which is how the tests kill and restore a stream.
"""

from __future__ import annotations

import contextlib
import socket
import struct
import threading
import time
from fractions import Fraction
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import av
import cv2

from sources.synthetic import SyntheticScene

RTP_MAX_PAYLOAD = 1400


def _listen(port: int) -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind(("127.0.0.1", port))
    sock.listen(4)
    return sock


def _nal_units(annexb: bytes) -> list[bytes]:
    """Split an Annex B byte stream on its start codes."""
    units, start, i = [], None, 0
    while True:
        j = annexb.find(b"\x00\x00\x01", i)
        if j < 0:
            break
        if start is not None:
            units.append(annexb[start:j].rstrip(b"\x00"))
        start = i = j + 3
    if start is not None:
        units.append(annexb[start:])
    return [unit for unit in units if unit]


def _rtp_payloads(nal: bytes) -> list[bytes]:
    """One NAL unit as RTP payloads: itself if it fits, else FU-A fragments."""
    if len(nal) <= RTP_MAX_PAYLOAD:
        return [nal]
    indicator, nal_type, body = (nal[0] & 0xE0) | 28, nal[0] & 0x1F, nal[1:]
    chunks = [body[i:i + RTP_MAX_PAYLOAD] for i in range(0, len(body), RTP_MAX_PAYLOAD)]
    payloads = []
    for k, chunk in enumerate(chunks):
        header = nal_type | (0x80 if k == 0 else 0) | (0x40 if k == len(chunks) - 1 else 0)
        payloads.append(bytes([indicator, header]) + chunk)
    return payloads


class _RtspSession:
    """One client connection: answers requests and, after PLAY, streams RTP on channel 0."""

    def __init__(self, server: RtspTestServer, conn: socket.socket) -> None:
        self.server, self.conn = server, conn
        self.send_lock = threading.Lock()
        self.playing = threading.Event()
        self.closed = threading.Event()
        self.rfile = conn.makefile("rb")

    def serve(self) -> None:
        streamer = threading.Thread(target=self._stream, name="rtsp-test-stream", daemon=True)
        streamer.start()
        try:
            while not self.closed.is_set():
                request = self._read_request()
                if request is None:
                    break
                self._answer(*request)
        except OSError:
            pass
        finally:
            self.close()
            streamer.join(timeout=2)

    def close(self) -> None:
        self.closed.set()
        self.playing.set()
        with contextlib.suppress(OSError):
            self.conn.shutdown(socket.SHUT_RDWR)
        self.conn.close()

    def _read_request(self) -> tuple[str, dict[str, str]] | None:
        while True:
            first = self.rfile.read(1)
            if not first:
                return None
            if first != b"$":  # not interleaved binary (RTCP from the client): a request line
                break
            _channel, length = struct.unpack(">BH", self.rfile.read(3))
            self.rfile.read(length)
        line = first + self.rfile.readline()
        headers = {}
        while (header := self.rfile.readline().strip()):
            name, _, value = header.decode().partition(":")
            headers[name.strip().lower()] = value.strip()
        if int(headers.get("content-length", 0)):
            self.rfile.read(int(headers["content-length"]))
        return line.decode().split(" ")[0], headers

    def _answer(self, method: str, headers: dict[str, str]) -> None:
        extra, body = {}, b""
        status = "200 OK"
        if method == "OPTIONS":
            extra["Public"] = "OPTIONS, DESCRIBE, SETUP, PLAY, TEARDOWN, GET_PARAMETER"
        elif method == "DESCRIBE":
            body = self.server.sdp().encode()
            extra.update({"Content-Type": "application/sdp", "Content-Base": self.server.url + "/"})
        elif method == "SETUP":
            if "interleaved" not in headers.get("transport", ""):
                status = "461 Unsupported Transport"
            extra.update({"Transport": "RTP/AVP/TCP;unicast;interleaved=0-1", "Session": "12345678;timeout=60"})
        elif method in ("PLAY", "GET_PARAMETER"):
            extra["Session"] = "12345678"
        elif method != "TEARDOWN":
            status = "501 Not Implemented"
        lines = [f"RTSP/1.0 {status}", f"CSeq: {headers.get('cseq', '0')}",
                 *(f"{k}: {v}" for k, v in extra.items()), f"Content-Length: {len(body)}", "", ""]
        with self.send_lock:
            self.conn.sendall("\r\n".join(lines).encode() + body)
        if method == "PLAY":
            self.playing.set()
        elif method == "TEARDOWN":
            self.closed.set()

    def _stream(self) -> None:
        self.playing.wait()
        server = self.server
        codec = av.CodecContext.create("libx264", "w")
        codec.width, codec.height, codec.pix_fmt = server.width, server.height, "yuv420p"
        codec.time_base, codec.framerate = Fraction(1, server.fps), Fraction(server.fps)
        codec.options = {"preset": "ultrafast", "tune": "zerolatency", "g": str(server.fps), "bf": "0"}
        seq, index, period, start = 0, 0, 1.0 / server.fps, time.monotonic()
        try:
            while not self.closed.is_set():
                frame = av.VideoFrame.from_ndarray(server.scene.render(index), format="bgr24")
                frame.pts = index
                data = b"".join(bytes(packet) for packet in codec.encode(frame))
                payloads = [p for nal in _nal_units(data) for p in _rtp_payloads(nal)]
                timestamp = index * 90000 // server.fps
                for k, payload in enumerate(payloads):
                    marker = 0x80 if k == len(payloads) - 1 else 0
                    packet = struct.pack(">BBHII", 0x80, marker | 96, seq & 0xFFFF, timestamp, 0x1234ABCD) + payload
                    seq += 1
                    with self.send_lock:
                        self.conn.sendall(struct.pack(">BBH", 0x24, 0, len(packet)) + packet)
                index += 1
                self.closed.wait(max(0.0, start + index * period - time.monotonic()))
        except OSError:
            self.closed.set()


class RtspTestServer:
    """An RTSP server on 127.0.0.1 serving one H.264 stream at ``rtsp://127.0.0.1:PORT/live``."""

    def __init__(self, width: int = 320, height: int = 240, fps: int = 15) -> None:
        self.width, self.height, self.fps = width, height, fps
        self.scene = SyntheticScene(width, height, seed=3)
        self.port = 0
        self._sock: socket.socket | None = None
        self._sessions: list[_RtspSession] = []
        self._threads: list[threading.Thread] = []

    @property
    def url(self) -> str:
        return f"rtsp://127.0.0.1:{self.port}/live"

    def sdp(self) -> str:
        return "\r\n".join(["v=0", "o=- 0 0 IN IP4 127.0.0.1", "s=uav-tui test stream", "c=IN IP4 0.0.0.0",
                            "t=0 0", "m=video 0 RTP/AVP 96", "a=rtpmap:96 H264/90000",
                            "a=fmtp:96 packetization-mode=1", "a=control:track0", ""])

    def start(self) -> None:
        """Listen (again, on the same port after a stop)."""
        self._sock = _listen(self.port)
        self.port = self._sock.getsockname()[1]
        thread = threading.Thread(target=self._accept, args=(self._sock,), name="rtsp-test-accept", daemon=True)
        thread.start()
        self._threads.append(thread)

    def stop(self) -> None:
        """Kill the stream: close the listening socket and drop every client."""
        if self._sock is not None:
            with contextlib.suppress(OSError):
                self._sock.shutdown(socket.SHUT_RDWR)
            self._sock.close()
            self._sock = None
        for session in self._sessions:
            session.close()
        for thread in self._threads:
            thread.join(timeout=3)
        self._sessions.clear()
        self._threads.clear()

    def _accept(self, sock: socket.socket) -> None:
        while True:
            try:
                conn, _ = sock.accept()
            except OSError:
                return
            session = _RtspSession(self, conn)
            self._sessions.append(session)
            thread = threading.Thread(target=session.serve, name="rtsp-test-session", daemon=True)
            thread.start()
            self._threads.append(thread)


class MjpegTestServer:
    """Multipart JPEG over HTTP at ``http://127.0.0.1:PORT/stream.mjpg``."""

    def __init__(self, width: int = 320, height: int = 240, fps: int = 15) -> None:
        self.scene = SyntheticScene(width, height, seed=4)
        self.fps = fps
        self.port = 0
        self._httpd: ThreadingHTTPServer | None = None
        self._thread: threading.Thread | None = None
        self._stopping = threading.Event()
        self.frozen = threading.Event()
        """While set, connections stay open but no data is sent: a stream that hangs."""

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}/stream.mjpg"

    def start(self) -> None:
        server = self

        class Handler(BaseHTTPRequestHandler):
            def do_GET(self) -> None:  # noqa: N802 - http.server's name
                self.send_response(200)
                self.send_header("Content-Type", "multipart/x-mixed-replace; boundary=frame")
                self.end_headers()
                index, start = 0, time.monotonic()
                with contextlib.suppress(OSError):
                    while not server._stopping.is_set():
                        if server.frozen.is_set():
                            server._stopping.wait(0.05)
                            continue
                        jpeg = cv2.imencode(".jpg", server.scene.render(index))[1].tobytes()
                        self.wfile.write(b"--frame\r\nContent-Type: image/jpeg\r\n"
                                         + f"Content-Length: {len(jpeg)}\r\n\r\n".encode() + jpeg + b"\r\n")
                        index += 1
                        server._stopping.wait(max(0.0, start + index / server.fps - time.monotonic()))

            def log_message(self, *args: object) -> None:
                pass

        self._stopping.clear()
        self._httpd = ThreadingHTTPServer(("127.0.0.1", self.port), Handler)
        self._httpd.daemon_threads = True
        self.port = self._httpd.server_address[1]
        self._thread = threading.Thread(target=self._httpd.serve_forever, name="mjpeg-test", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        if self._httpd is None:
            return
        self._stopping.set()
        self._httpd.shutdown()
        self._httpd.server_close()
        assert self._thread is not None
        self._thread.join(timeout=3)
        self._httpd = None
