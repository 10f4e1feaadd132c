"""Error messages on one line: the one formatter every room of ``bridge`` and the command line use.

A message that reaches a user (a table cell, a JSON ``error`` field, a line ``occsurf: PATH: reason``
on stderr) must fit on one line whatever the exception's text holds (OCC messages often span
several); :func:`strip_path` drops the leading ``PATH:`` (and its blank) from a message shown beside its path. Only
the standard library is imported here, so the command-line process can use it
without loading NumPy or OCC.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

__all__ = ["one_line", "error_line", "strip_path"]


def one_line(err: BaseException | str, *, expected: tuple[type[BaseException], ...] = ()) -> str:
    """An exception (or a text) as one line.

    Every run of white space (line breaks included) becomes one space. An exception is shown as
    ``'TypeName: message'``, or ``'TypeName'`` when its message is empty, unless it is an instance
    of one of the ``expected`` types: their messages are written for the user (occsurf's own
    errors name the argument and the path) and are shown alone.

    Parameters
    ----------
    err : BaseException or str
        The exception, or a text (taken as it is, but for the white space).
    expected : tuple of exception types, optional
        Exceptions shown by their message alone (the command line passes
        ``(OccsurfError, OSError)``); default none, every exception keeps its type name.

    Returns
    -------
    str
        Never empty: ``'unknown error'`` for an empty text.

    Examples
    --------
    >>> one_line(RuntimeError("boom\\nsecond line"))
    'RuntimeError: boom second line'
    >>> one_line(ValueError("bad  value"), expected=(ValueError,))
    'bad value'
    """
    if isinstance(err, BaseException):
        text = str(err).strip()
        if not (text and isinstance(err, expected)):
            text = f"{type(err).__name__}: {text}" if text else type(err).__name__
    else:
        text = str(err)
    return " ".join(text.split()) or "unknown error"


def error_line(err: BaseException | str) -> str:
    """:func:`one_line` as occsurf reports errors to users (the command line, the worker process).

    occsurf's own errors (:class:`~occsurf.algorithms.errors.OccsurfError`, whose messages name
    the argument or the path) and :class:`OSError` are shown by their message alone; any other
    exception keeps its type name (``'RuntimeError: boom'``): it was not expected.
    """
    if not isinstance(err, BaseException):
        return one_line(err)
    try:
        from occsurf.algorithms.errors import OccsurfError
    except Exception:  # noqa: BLE001 - a broken install must not hide the error being reported
        return one_line(err, expected=(OSError,))
    return one_line(err, expected=(OccsurfError, OSError))


def strip_path(message: str, path: str | os.PathLike[str]) -> str:
    """``message`` without a leading ``PATH: ``: for a caller that shows the path beside the message
    (a table's file heading, ``occsurf: PATH: reason``). ``path`` is matched as given, resolved and
    absolute; a message that does not start with it is returned unchanged.
    """
    path = Path(path)
    candidates = {str(path), os.fspath(path)}
    with contextlib.suppress(OSError, RuntimeError):  # RuntimeError: a loop of symlinks (Python 3.11 resolve)
        candidates.add(str(path.resolve()))
        candidates.add(str(path.absolute()))
    for c in sorted(candidates, key=len, reverse=True):
        if message.startswith(c + ": "):
            return message[len(c) + 2 :]
    return message
