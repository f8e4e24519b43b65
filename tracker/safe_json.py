"""Reading JSON a user gave us: size and depth limits, numbers checked, types exact.

:func:`read` / :func:`parse` turn a file (or text) into plain Python values or raise a one-line
error naming the file: too large, not UTF-8, bad syntax (with line and column), nested deeper
than ``max_depth``, a number literal longer than :data:`MAX_NUMBER_CHARS` characters (Python's
own int conversion gives up past 4300 digits with a traceback), ``NaN`` / ``Infinity`` (not JSON,
but Python's parser takes them) and numbers that overflow a float (``1e400``). The checkers
(:func:`number`, :func:`integer`, :func:`numbers`, :func:`string`, :func:`mapping`,
:func:`sequence`) then take one value each: exact types (no strings or booleans where numbers
go), finite, inside a range. Every function raises ``error`` (default :class:`JSONInputError`),
so each format raises its own exception type (``ClicksError``, ``ArtSetError`` …).

Standard library only: ``art_sets`` keeps an identical copy (it may not import ``tracker``;
``tests/test_file_safety.py`` keeps the two equal).
"""

from __future__ import annotations

import json
import math
import numbers as _numbers
import os
from pathlib import Path
from typing import Any

MAX_BYTES = 16 * 1024 * 1024
MAX_DEPTH = 32
"""Deepest nesting of arrays and objects accepted (our formats use at most 5)."""
MAX_NUMBER_CHARS = 64
"""Longest number literal accepted (a double has 17 significant digits)."""
MAGNITUDE = 1e9
"""Default bound on the size of a number (pixels, frames, weights are all far below it)."""
MAX_STRING = 4096


class JSONInputError(ValueError):
    """A JSON file or value that cannot be used; the message is one line."""


def show(v: Any, limit: int = 60) -> str:
    """A short one-line ``repr`` of ``v`` for error messages."""
    try:
        r = repr(v)
    except (ValueError, RecursionError):  # an int beyond Python's digit limit, a deep list
        r = f"<{type(v).__name__}>"
    r = " ".join(r.split())
    return r if len(r) <= limit else r[: limit - 1] + "…"


def _check_literal(s: str) -> None:
    if len(s) > MAX_NUMBER_CHARS:
        raise _Bad(f"a number of {len(s)} characters ({s[:12]}…)")


class _Bad(Exception):
    pass


def _parse_int(s: str) -> int:
    _check_literal(s)
    return int(s)


def _parse_float(s: str) -> float:
    _check_literal(s)
    v = float(s)
    if not math.isfinite(v):
        raise _Bad(f"the number {s} is out of range")
    return v


def _parse_constant(s: str) -> float:
    raise _Bad(f"{s} is not a number JSON allows")


def _parse_nan(s: str) -> float:
    if s == "NaN":
        return math.nan
    return _parse_constant(s)


def _depth_over(value: Any, limit: int) -> bool:
    stack = [(value, 1)]
    while stack:
        v, d = stack.pop()
        if isinstance(v, dict):
            v = list(v.values())
        elif not isinstance(v, list):
            continue
        if d > limit:
            return True
        stack.extend((x, d + 1) for x in v if isinstance(x, (list, dict)))
    return False


def parse(
    text: str | bytes,
    where: str,
    *,
    max_depth: int = MAX_DEPTH,
    allow_nan: bool = False,
    error: type[Exception] = JSONInputError,
) -> Any:
    """Parse JSON ``text``; ``where`` (usually the file) starts every error message.

    ``allow_nan`` reads ``NaN`` (which Python's ``json.dumps`` writes for a missing measurement)
    as a float NaN for the checkers to judge; ``Infinity`` and overflowing numbers are refused
    either way.
    """
    try:
        if isinstance(text, bytes):
            text = text.decode("utf-8-sig")
        elif text.startswith("\ufeff"):
            text = text[1:]
    except UnicodeDecodeError as e:
        raise error(f"{where}: not UTF-8 text (byte {e.start})") from None
    try:
        constant = _parse_nan if allow_nan else _parse_constant
        value = json.loads(text, parse_int=_parse_int, parse_float=_parse_float, parse_constant=constant)
    except json.JSONDecodeError as e:
        raise error(f"{where}: not valid JSON (line {e.lineno} column {e.colno}: {e.msg})") from None
    except _Bad as e:
        raise error(f"{where}: not valid JSON ({e})") from None
    except RecursionError:
        raise error(f"{where}: not valid JSON (nested deeper than {max_depth} levels)") from None
    if _depth_over(value, max_depth):
        raise error(f"{where}: not valid JSON (nested deeper than {max_depth} levels)")
    return value


def read(
    path: str | os.PathLike,
    what: str = "file",
    *,
    max_bytes: int = MAX_BYTES,
    max_depth: int = MAX_DEPTH,
    allow_nan: bool = False,
    error: type[Exception] = JSONInputError,
) -> Any:
    """Read and :func:`parse` the JSON file ``path``; ``what`` names it in messages
    ("cannot read ``what``")."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            data = f.read(max_bytes + 1)
    except IsADirectoryError:
        raise error(f"{path}: cannot read {what} (it is a folder)") from None
    except OSError as e:
        raise error(f"{path}: cannot read {what} ({e.strerror or type(e).__name__})") from None
    except (ValueError, RuntimeError) as e:  # NUL in the path, a symlink loop on some systems
        raise error(f"{path}: cannot read {what} ({' '.join(str(e).split())})") from None
    if len(data) > max_bytes:
        raise error(f"{path}: {what} is larger than {max_bytes // (1024 * 1024)} MB; refused")
    return parse(data, str(path), max_depth=max_depth, allow_nan=allow_nan, error=error)


# ------------------------------------------------------------------------------- checkers
def _real(v: Any) -> bool:
    """A number: what JSON parses to, or a numpy scalar from Python callers; never a boolean."""
    return isinstance(v, _numbers.Real) and not isinstance(v, bool) and type(v).__name__ != "bool_"


def number(
    v: Any,
    what: str,
    error: type[Exception] = JSONInputError,
    lo: float = -MAGNITUDE,
    hi: float = MAGNITUDE,
    nan_ok: bool = False,
) -> float:
    """``v`` as a float if it is a JSON number (not a boolean) in ``[lo, hi]`` (or NaN, with
    ``nan_ok``: a value that was not measured)."""
    if not _real(v):
        raise error(f"{what} must be a number, got {show(v)}")
    try:
        f = float(v)
    except OverflowError:
        f = math.inf
    if nan_ok and math.isnan(f):
        return f
    if not (math.isfinite(f) and lo <= f <= hi):
        raise error(f"{what} must be a number from {lo:g} to {hi:g}, got {show(v)}")
    return f


def integer(
    v: Any, what: str, error: type[Exception] = JSONInputError, lo: int = -int(MAGNITUDE), hi: int = int(MAGNITUDE)
) -> int:
    """``v`` as an int if it is a whole JSON number (``3`` or ``3.0``, not ``true``) in ``[lo, hi]``."""
    if not _real(v) or not (isinstance(v, _numbers.Integral) or _whole(v)):
        raise error(f"{what} must be a whole number, got {show(v)}")
    if not lo <= v <= hi:
        raise error(f"{what} must be a whole number from {lo} to {hi}, got {show(v)}")
    return int(v)


def _whole(v: Any) -> bool:
    try:
        return float(v).is_integer()
    except OverflowError:
        return False


def numbers(
    v: Any, what: str, n: int, error: type[Exception] = JSONInputError, lo: float = -MAGNITUDE, hi: float = MAGNITUDE
) -> tuple[float, ...]:
    """``v`` as ``n`` floats if it is a list (or tuple) of exactly ``n`` numbers in ``[lo, hi]``."""
    if not isinstance(v, (list, tuple)) or len(v) != n or not all(_real(x) for x in v):
        raise error(f"{what} must be a list of {n} numbers, got {show(v)}")
    return tuple(number(x, what, error, lo, hi) for x in v)


def string(v: Any, what: str, error: type[Exception] = JSONInputError, max_len: int = MAX_STRING) -> str:
    """``v`` if it is a string of at most ``max_len`` characters."""
    if not isinstance(v, str):
        raise error(f"{what} must be a string, got {show(v)}")
    if len(v) > max_len:
        raise error(f"{what} is {len(v)} characters long; at most {max_len} are allowed")
    return v


def mapping(v: Any, what: str, error: type[Exception] = JSONInputError) -> dict:
    """``v`` if it is a JSON object."""
    if not isinstance(v, dict):
        raise error(f"{what} must be a JSON object, got {show(v)}")
    return v


def sequence(v: Any, what: str, error: type[Exception] = JSONInputError, max_len: int = 1_000_000) -> list:
    """``v`` if it is a JSON array of at most ``max_len`` items."""
    if not isinstance(v, list):
        raise error(f"{what} must be a list, got {show(v)}")
    if len(v) > max_len:
        raise error(f"{what} has {len(v)} items; at most {max_len} are allowed")
    return v
