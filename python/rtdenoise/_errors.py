"""rtdenoise's exceptions. The native module raises them through error_for()."""

from __future__ import annotations

import enum


class ErrorCode(enum.IntEnum):
    """Why a call failed: the C API's RTDError values, then the readers' and writers' own."""

    NONE = 0
    UNKNOWN = 1
    INVALID_ARGUMENT = 2  # a bad name, a value out of range, a wrong shape or type
    INVALID_OPERATION = 3  # a call in the wrong order
    INVALID_INPUT = 4  # a frame's or a file's content: IDs out of range, channels, sizes
    OUT_OF_MEMORY = 5
    UNSUPPORTED_DEVICE = 6  # no CUDA back end in this build, or no GPU
    DEVICE_FAILURE = 7  # the GPU reported an error
    MISSING_FILE = 100  # readers: a file the layout requires is not there
    IO_FAILURE = 101  # readers and writers: a truncated file, an unwritable folder
    MISSING_TOOL = 102  # an external program is not installed


class Error(RuntimeError):
    """A failure of rtdenoise: ``code`` (an ErrorCode) and ``message``, which names the setting,
    the image or the file, and the problem."""

    def __init__(self, message: str, code: ErrorCode = ErrorCode.UNKNOWN):
        super().__init__(message)
        self.message = message
        self.code = ErrorCode(code)

    def __str__(self) -> str:
        return self.message

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.message!r}, {self.code!s})"

    def __reduce__(self):  # pickles (multiprocessing) with its code
        return (type(self), (self.message, self.code))


class InvalidArgumentError(Error, ValueError):
    """A bad setting name or value, a wrong shape or dtype, a missing input (code
    INVALID_ARGUMENT)."""

    def __init__(self, message: str, code: ErrorCode = ErrorCode.INVALID_ARGUMENT):
        super().__init__(message, code)


class MissingFileError(Error, FileNotFoundError):
    """A file a sequence's layout requires is not there (code MISSING_FILE)."""

    def __init__(self, message: str, code: ErrorCode = ErrorCode.MISSING_FILE):
        super().__init__(message, code)


_CLASSES = {
    ErrorCode.INVALID_ARGUMENT: InvalidArgumentError,
    ErrorCode.MISSING_FILE: MissingFileError,
}


for _class in (ErrorCode, Error, InvalidArgumentError, MissingFileError):
    _class.__module__ = "rtdenoise"  # as users name them: rtdenoise.Error


def error_for(code: int, message: str) -> Error:
    """The exception for an error code and message (called by the native module)."""
    try:
        code = ErrorCode(code)
    except ValueError:
        code = ErrorCode.UNKNOWN
    return _CLASSES.get(code, Error)(message, code)
