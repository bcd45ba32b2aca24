"""The command line's parser: argparse with short errors that suggest the flag (or tool) that was meant.

Python 3.11's argparse has no ``suggest_on_error``: a misspelt flag (``--max-sped 2``) got the whole
usage, 20 lines, and no hint. :class:`ArgumentParser` prints one line instead, with ``did you mean``.
"""

from __future__ import annotations

import argparse
import difflib
import re
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

from uav_tui.output.text import safe


class ArgumentParser(argparse.ArgumentParser):
    """argparse's parser, whose errors are one line: the closest flag when one was misspelt, else where to look.

    Args:
        suggest: words that may stand where a flag did not parse, besides the flags (the tools' names).
    """

    def __init__(self, *args: Any, suggest: Sequence[str] = (), **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.suggest = tuple(suggest)

    def error(self, message: str) -> NoReturn:
        hint = self._suggestion(message) or f" (`{self.prog} --help` lists the options)"
        print(f"{self.prog}: error: {safe(message)}{hint}", file=sys.stderr)
        sys.exit(2)

    def _suggestion(self, message: str) -> str:
        unknown = re.match(r"unrecognized arguments: (.*)", message)
        if unknown is None:
            return ""
        flags = [flag for action in self._actions for flag in action.option_strings if flag.startswith("--")]
        for word in unknown.group(1).split():
            name = word.split("=", 1)[0]
            candidates = flags if name.startswith("-") else list(self.suggest)
            close = difflib.get_close_matches(name, candidates, n=1, cutoff=0.7)
            if close:
                shown = close[0] if name.startswith("-") else f"{self.prog} {close[0]}"
                return f"; did you mean {shown}?"
        return ""
