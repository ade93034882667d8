"""lambert's exceptions: one base, :class:`LambertError`, and subclasses
that are also the built-in exception a Python user expects, so that
``except ValueError`` and ``except lambert.LambertError`` both catch a bad
argument. Messages name the argument (or the file and line)."""


class LambertError(Exception):
    """Base of every exception lambert raises itself."""


class LambertValueError(LambertError, ValueError):
    """A bad value: a NaN or huge coordinate, a shape, a size, a malformed
    file's content (naming the file and line or field)."""


class LambertTypeError(LambertError, TypeError):
    """An argument of the wrong type (a string where a number goes, ...)."""


class LambertOSError(LambertError, OSError):
    """A file that cannot be read or written."""


class LambertFileNotFoundError(LambertOSError, FileNotFoundError):
    """A file that does not exist."""


class LambertPermissionError(LambertOSError, PermissionError):
    """A file that may not be read or written."""


class LambertNotADirectoryError(LambertOSError, NotADirectoryError):
    """A file where a folder of an output's path should be."""


class LambertRuntimeError(LambertError, RuntimeError):
    """The device failed (no adapter, a driver's limit), or an internal
    error (a bug: please report it)."""


__all__ = [
    "LambertError",
    "LambertValueError",
    "LambertTypeError",
    "LambertOSError",
    "LambertFileNotFoundError",
    "LambertPermissionError",
    "LambertNotADirectoryError",
    "LambertRuntimeError",
]
