"""Outside text made safe: escaped, redacted, bounded (uav_tui/output/text.py)."""

from __future__ import annotations

import logging
import sys

import pytest

from uav_tui.output.text import SafeFormatter, describe, escape, redact, shorten


@pytest.mark.parametrize(("raw", "shown"), [
    ("plain text", "plain text"),
    ("\x1b[2J\x1b[H", "\\x1b[2J\\x1b[H"),
    ("a\nb\r\tc\x00\x07\x7f", "a\\nb\\r\\tc\\x00\\x07\\x7f"),
    ("\x9b31m", "\\x9b31m"),  # the one-byte C1 CSI
    ("name\u202etxt.exe", "name\\u202etxt.exe"),  # right-to-left override
    ("line\u2028[info] forged", "line\\u2028[info] forged"),
    ("caf\u00e9 \u00fcber \u6771\u4eac", "caf\u00e9 \u00fcber \u6771\u4eac"),  # printable text is left alone
], ids=["plain", "csi", "c0", "c1", "bidi", "line-separator", "unicode"])
def test_escape_shows_control_characters(raw: str, shown: str) -> None:
    assert escape(raw) == shown
    assert escape(escape(raw)) == shown  # applying it at two boundaries changes nothing


def test_multiline_keeps_lines_but_none_starts_at_the_margin() -> None:
    text = "Traceback (most recent call last):\n  File \"x.py\"\nValueError: x\x1b[2J\n[info] command: arm"
    lines = escape(text, multiline=True).splitlines()
    assert lines[0] == "Traceback (most recent call last):"
    assert all(line.startswith("  ") for line in lines[1:]) and "\\x1b[2J" in lines[2]


@pytest.mark.parametrize(("raw", "shown"), [
    ("source rtsp://admin:Hunter2pw@192.0.2.1:554/s", "source rtsp://admin:***@192.0.2.1:554/s"),
    ("rtsp://u:p@ss@host/a", "rtsp://u:***@host/a"),
    ("rtsp://admin:Leak2/pw@host/live", "rtsp://admin:***@host/live"),
    ("rtsp://admin:Le@k/2?#x@host:554/live?x=1", "rtsp://admin:***@host:554/live?x=1"),
    ("rtsp://admin:P@ss#1@[2001:db8::1]:554/s", "rtsp://admin:***@[2001:db8::1]:554/s"),
    ("rtsp://me@mail.example:pw@host/live", "rtsp://me@mail.example:***@host/live"),
    ("rtsp://u:p@host/a@b", "rtsp://u:***@b"),  # an @ in the path: hidden with the password, never a password shown
    ("http://192.0.2.1:8080/?token=abc&x=1", "http://192.0.2.1:8080/?token=***&x=1"),
    ("rtsp://h/live?pwd=1&pass=2&passwd=3&password=4&channel=1", "rtsp://h/live?pwd=***&pass=***&passwd=***&password=***"
                                                                 "&channel=1"),
    ("http://h/s?api_key=1&access_token=2&x-auth=3&secret=4&sig=5&monkey=6", "http://h/s?api_key=***&access_token=***"
                                                                           "&x-auth=***&secret=***&sig=***&monkey=6"),
    ('{"uri": "rtsp://a:b@h", "other": "x@y"}', '{"uri": "rtsp://a:***@h", "other": "x@y"}'),
    ("rtsp://host/stream and usb:0 and mail@example.org", "rtsp://host/stream and usb:0 and mail@example.org"),
    ("rtsp://192.0.2.1:554/s?user=me@mail.example", "rtsp://192.0.2.1:554/s?user=me@mail.example"),
    ("rtsp://admin:1234/x@host/s", "rtsp://admin:***@host/s"),
    ("opening rtsp://admin:pa ss@cam/live now", "opening rtsp://admin:***@cam/live now"),
    ('source rtsp://admin:pa"ss@cam', "source rtsp://admin:***@cam"),
    ("rtsp://admin:sec'ret@cam:554/s", "rtsp://admin:***@cam:554/s"),
    ("<rtsp://admin:sec<ret>@cam/s>", "<rtsp://admin:***@cam/s>"),
    ('{"source": "rtsp://admin:pa\\"ss@cam/live", "x": 1}', '{"source": "rtsp://admin:***@cam/live", "x": 1}'),
    ('{"uri": "rtsp://cam:x", "mail": "me@example.org"}', '{"uri": "rtsp://cam:x", "mail": "me@example.org"}'),
    ("rtsp://192.0.2.1:554/s failed, mail me@example.org", "rtsp://192.0.2.1:554/s failed, mail me@example.org"),
    ("rtsp://cam:554 and me@example.org", "rtsp://cam:554 and me@example.org"),
    ("http://h/live#token=abc&x=1", "http://h/live#token=***&x=1"),
    ("http://h/cb#access_token=abc", "http://h/cb#access_token=***"),
    ("tcp://127.0.0.1:5760, operator pilot@site.org", "tcp://127.0.0.1:5760, operator pilot@site.org"),
    ("connect udp://:14540: timed out; ssh pi@raspberrypi.local",
     "connect udp://:14540: timed out; ssh pi@raspberrypi.local"),
    ('{"a": "rtsp://u:p\\\\", "b@host/": 1}', '{"a": "rtsp://u:p\\\\", "b@host/": 1}'),
], ids=["uri", "at-in-password", "slash-in-password", "any-character", "at-in-user", "ipv6",
        "at-in-path", "token",
        "password-parameters", "prefixed-parameters", "json", "nothing-secret", "at-in-query",
        "digits-and-slash", "space-in-password", "quote-in-password", "apostrophe-in-password",
        "bracket-in-password", "escaped-quote-in-json", "json-keys-kept", "port-path-then-mail",
        "port-then-mail", "fragment-token", "fragment-access-token", "port-comma-then-mail",
        "no-host-port-then-mail", "escaped-backslash-ends-json-string"])
def test_redact(raw: str, shown: str) -> None:
    assert redact(raw) == shown


@pytest.mark.parametrize(("value", "shown"), [
    (tuple(range(10**6)), "(0, 1, 2, 3, ...) (1000000 items)"),
    ((0.5, 10**400, 1), "(0.5, 1000000000...00000000000, 1)"),
    ("x" * 10**6, None),
    ("\x1b[2J", "'\\x1b[2J'"),
    (10**100_000, "<int>"),  # too many digits for str(): still described
], ids=["huge-tuple", "huge-int", "huge-str", "escapes", "unprintable-int"])
def test_describe_is_bounded(value: object, shown: str | None) -> None:
    text = describe(value)
    assert len(text) <= 80 and "\x1b" not in text
    if shown is not None:
        assert text == shown


def test_describe_survives_a_broken_repr() -> None:
    class Broken:
        def __repr__(self) -> str:
            raise RuntimeError("no")

    assert describe(Broken()).startswith("<Broken")


def test_shorten_says_what_it_left_out() -> None:
    assert shorten("abc", 5) == "abc"
    assert shorten("a" * 10, 4) == "aaaa... (6 more characters)"


def test_safe_formatter_escapes_messages_and_indents_tracebacks() -> None:
    formatter = SafeFormatter("%(levelname)s %(message)s")
    try:
        raise ValueError("bad\n[info] command: arm")
    except ValueError:
        record = logging.LogRecord("x", logging.ERROR, __file__, 1, "got %s", ("rtsp://a:pw@h\x1b[2J",),
                                   sys.exc_info())
    lines = formatter.format(record).splitlines()
    assert lines[0] == "ERROR got rtsp://a:***@h\\x1b[2J"
    assert all(line.startswith("  ") for line in lines[1:]) and "  [info] command: arm" in lines
