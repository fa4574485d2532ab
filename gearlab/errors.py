"""Errors that the CLI turns into one clear line and exit code 2, and the "did you mean" of an
unknown name."""

import difflib
import math
import re
from contextlib import contextmanager

# Line breaks and other control characters; they reach messages inside names taken from the
# user's files (a TOML key "a\nb", a channel name in an HDF5 file).
_CONTROL = re.compile(r"[\x00-\x1f\x7f\x85\u2028\u2029]")


def one_line(text: str) -> str:
    """*text* with its control characters escaped, so that it prints as one line."""
    return _CONTROL.sub(lambda m: ascii(m.group())[1:-1], text)


def shown(value: object, limit: int = 60) -> str:
    """repr() of a value from the input, cut to *limit* characters (a 4000-digit integer, a
    long text) so that the message stays readable."""
    if isinstance(value, int) and value.bit_length() > 100:  # repr() refuses beyond 4300 digits
        return f"an integer of about {round(value.bit_length() * math.log10(2))} digits"
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def clipped(text: str, limit: int = 200) -> str:
    """*text* (a library's message, which may quote the input) cut to *limit* characters."""
    return text if len(text) <= limit else text[: limit - 3] + "..."


MESSAGE_MAX = 600  # characters of an error line; a longer one quotes too much of the input


def _short(text: str) -> str:
    """*text*, its middle cut out when it is too long: the start says where, the end what was
    expected, the middle is mostly a value quoted from the input."""
    if len(text) <= MESSAGE_MAX:
        return text
    return f"{text[: MESSAGE_MAX * 2 // 3]} ... {text[-MESSAGE_MAX // 3 :]}"


class GearlabInputError(Exception):
    """Bad input from the user: a scenario, a CLI option, a data file, a plugin parameter.

    The message is one line that says what is wrong, where (file, table, key) and what
    was expected. The CLI prints it and exits with code 2; nothing is half-written.
    Whatever the message quotes from the input, it stays on one line.
    """

    def __init__(self, message: object = "", *args):
        super().__init__(_short(one_line(str(message))), *args)


@contextmanager
def prefixed(prefix: str):
    """Re-raise GearlabInputError from the shared pipeline with the file (and channel) in front."""
    try:
        yield
    except GearlabInputError as exc:
        raise GearlabInputError(f"{prefix}: {exc}") from None


class UnknownPluginError(GearlabInputError):
    """A plugin name that no registered plugin of that kind carries."""


def did_you_mean(name: str, known: list[str] | tuple[str, ...], named: dict[str, str] | None = None) -> str:
    """' (did you mean 'x'?)' for the closest of *known*, said as *named* says it (an alias by its listed name)."""
    close = difflib.get_close_matches(name, list(known), n=1, cutoff=0.5)  # 0.5: 'q1' still finds 'q0'
    return f" (did you mean '{(named or {}).get(close[0], close[0])}'?)" if close else ""


def which_meant(name: str, available) -> str:
    """The hint after 'no channel NAME': the paths *name* ends, where it ends several (an HDF5's run1/acc and run2/acc
    asked as 'acc': the hint named one of them alone), else the closest name (did_you_mean)."""
    ends = [str(c) for c in available if str(c).rsplit("/", 1)[-1] == name and str(c) != name]
    if len(ends) > 1:
        return (
            f" ('{name}' ends {len(ends)} datasets' paths, {', '.join(ends[:-1])} and {ends[-1]}: give the whole path)"
        )
    return did_you_mean(name, [str(c) for c in available])


def refuse_unknown(given, known: list[str] | tuple[str, ...], where: str) -> None:
    """A one-line error for the first parameter of *given* that is not *known*: the closest known one and the list."""
    for key in given:
        if key not in known:
            raise GearlabInputError(
                f"{where}: unknown parameter '{key}'{did_you_mean(key, known)}; known: {', '.join(known) or 'none'}"
            )
