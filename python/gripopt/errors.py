"""gripopt's errors as Python exceptions.

Every error the library reports is a :class:`GripoptError` carrying gripopt's own message,
which names the file (or folder) and the field at fault, as the command line prints it.
The subclasses say what kind of error it is; ``exit_code`` is the code the ``gripopt``
command would have ended with (2: bad input, 1: a failed run).
"""

from __future__ import annotations

import os
import sys
import warnings
from typing import Any, Optional


class GripoptError(Exception):
    """An error of gripopt (the base class of every exception the package raises).

    Attributes:
        message: gripopt's message (names the file and the field).
        path: the file or folder the error is about, where there is one.
        field: the field of a problem file (e.g. ``object.radius``), where there is one.
        exit_code: the ``gripopt`` command's exit code for this error (2 bad input, 1 failure;
            when not given, the class's ``default_exit_code``).
    """

    #: The exit code of an error of this class raised without one (1: a failure).
    default_exit_code = 1

    def __init__(
        self,
        message: str,
        path: Optional[str] = None,
        field: Optional[str] = None,
        exit_code: Optional[int] = None,
    ) -> None:
        super().__init__(message)
        self.message = message
        self.path = path
        self.field = field
        self.exit_code = self.default_exit_code if exit_code is None else exit_code

    def __reduce__(self) -> tuple[Any, ...]:
        # keep the attributes through pickling (errors come back from Dask workers so)
        return (type(self), (self.message, self.path, self.field, self.exit_code))


class InputError(GripoptError, ValueError):
    """Bad input: a problem file, a design, an argument, a folder that cannot be used as
    asked (the command line's exit code 2)."""

    default_exit_code = 2


class ProblemError(InputError):
    """A problem file (or problem text) that is not valid TOML of the expected shape, or a
    field out of its range: ``path`` is the file, ``field`` the dotted field name."""


class RunFolderError(InputError):
    """A run folder that cannot be used as asked: it holds no run or already one, its
    checkpoint, run.json or a table is damaged, its inputs changed (an edited
    problem.toml), or it now holds another run than the one a :class:`~gripopt.Run` was
    opened on."""


class RunLockedError(RunFolderError):
    """Another gripopt process is running in the run folder (its lock is released when it
    ends, also when killed)."""


class RecordingError(InputError):
    """A recording (MCAP shard) that is missing, damaged or does not hold the design asked for."""


class RunStoppedError(GripoptError):
    """A run stopped before its last generation because something failed; its checkpoint
    allows ``gripopt.resume(path)`` (the message says whether there is one)."""


class GripoptWarning(UserWarning):
    """A note of a run: a recording recovered, the thread count, a resume forced."""


_PACKAGE = os.path.dirname(os.path.abspath(__file__)) + os.sep


def _warn(message: str) -> None:
    """A :class:`GripoptWarning` with ``message``, reported at the caller's line: the first
    frame outside the package (the native module's warnings included), never ``sys:1``."""
    level, frame = 1, sys._getframe(0)
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_PACKAGE):
        level, frame = level + 1, frame.f_back
    warnings.warn(message, GripoptWarning, stacklevel=level)


__all__ = [
    "GripoptError",
    "InputError",
    "ProblemError",
    "RunFolderError",
    "RunLockedError",
    "RecordingError",
    "RunStoppedError",
    "GripoptWarning",
]
