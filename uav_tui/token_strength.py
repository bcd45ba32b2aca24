"""How hard the web page's token is to guess: an entropy estimate, and the refusal of a weak one.

The estimate is zxcvbn's (Dropbox's password-strength estimator): log2 of the guesses needed by an attacker
who tries common passwords, words, names, keyboard walks, repeats, sequences and dates first. It is
conservative for random strings (about 3.3 bits a character, whatever the alphabet): the 32 characters of
``secrets.token_urlsafe(24)`` estimate about 106 bits, a 16-character repeated letter about 8.
"""

from __future__ import annotations

import math

MIN_TOKEN_BITS = 96
"""The least estimated entropy a configured ``web_token`` may have."""

GENERATE_TOKEN = 'python3 -c "import secrets; print(secrets.token_urlsafe(24))"'
"""A command that prints a token well above :data:`MIN_TOKEN_BITS` (192 random bits)."""

_ESTIMATED_CHARS = 72
"""zxcvbn refuses longer input; the estimate of a longer token is that of its first characters (a lower bound)."""


def token_bits(token: str) -> float:
    """The estimated entropy of ``token``, bits."""
    from zxcvbn import zxcvbn  # its word lists load in 50 ms: only when a token is configured

    return float(zxcvbn(token[:_ESTIMATED_CHARS])["guesses_log10"]) * math.log2(10)


TOKEN_CHARACTERS = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-._~")
"""What a token may hold: the characters a URL carries as they are (it travels in the page's address, a header and
a cookie), so it reaches the server whole."""


def token_problem(token: str) -> str | None:
    """Why ``token`` is not one (a character a URL cannot carry as it is) or too easy to guess; None when it is."""
    if bad := sorted(set(token) - TOKEN_CHARACTERS):
        shown = ", ".join(repr(c) for c in bad[:5])
        return (f"may hold only letters, digits and - . _ ~ (it travels in the page's address), not {shown}; "
                f"generate one with {GENERATE_TOKEN}")
    bits = token_bits(token)
    if bits >= MIN_TOKEN_BITS:
        return None
    return (f"is too easy to guess (about {bits:.0f} bits of entropy estimated, at least {MIN_TOKEN_BITS} needed); "
            f"generate one with {GENERATE_TOKEN}, or leave it empty for a random one per start")
