"""The exceptions of the package: every failure is one of these, with a message that names
the problem (the FMU, the variable, the time) and, for a failed FMU call, what the FMU
logged."""


class MbfmuError(Exception):
    """Base class of every error raised by mbfmu."""


class FMUNotFoundError(MbfmuError, FileNotFoundError):
    """The FMU (or SSP, or model) path does not exist."""


class ArgumentError(MbfmuError, ValueError):
    """An argument is unusable: a time before the start, an unknown variable name, ..."""


class NotLinearizableError(MbfmuError):
    """The FMU or system cannot be linearized (no <Derivatives>, a singular algebraic loop, ...)."""


class FMUCallError(MbfmuError):
    """An FMI call failed; the message carries the function, the time and the FMU's log."""
