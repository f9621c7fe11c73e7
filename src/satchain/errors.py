"""Exceptions raised by satchain.

Every exception derives from :class:`SatchainError` *and* from the matching built-in, so callers can
catch ``ValueError`` / ``OSError`` / ``MemoryError`` as usual (the GalSim habit). Messages name the
parameter, the value and what is allowed, e.g. ``optics.obscuration_ratio = 1.2: must be in [0, 1)``.
"""

from __future__ import annotations


class SatchainError(Exception):
    """Base class of every error satchain raises on purpose."""


class ConfigError(SatchainError, ValueError):
    """An invalid or inconsistent parameter (system description, run configuration, option)."""


class InputError(SatchainError, ValueError):
    """Input data that cannot be processed (an image without an edge, NaNs, a region that is too small)."""


class SatchainIOError(SatchainError, OSError):
    """A file that cannot be read or written."""


class ResourceLimitError(SatchainError, MemoryError):
    """Work refused up front because it would not fit in the allowed memory."""


class ParameterTypeError(ConfigError, TypeError):
    """A public function called with an argument of the wrong type (a string or a boolean where a number is
    wanted, None for an image, a file name where a truth record is wanted); also a ``TypeError``."""


class SatchainWarning(UserWarning):
    """An input used other than as it stands (a colour image converted to grey, page 1 of a multi-page TIFF, an
    implausible pixel size); the command line prints it as ``warning: ...``."""


class SatchainDeprecationWarning(DeprecationWarning):
    """A name satchain still accepts but will remove; the message names the version that deprecated it, the one
    that removes it, and what to use instead."""
