"""deflex's exceptions: one hierarchy under :class:`DeflexError`, each carrying the text the
CLI prints for the same problem (file, line or field named, what was expected)."""

from __future__ import annotations

__all__ = [
    "DeflexError",
    "InputError",
    "InputTypeError",
    "ModelError",
    "DataError",
    "CalibrationError",
    "CompensationError",
    "ProgramError",
    "SimulationError",
    "DeflexIOError",
    "InternalError",
]


class DeflexError(Exception):
    """Base class of every error deflex raises."""


class InputError(DeflexError, ValueError):
    """A bad argument: an array of the wrong shape, NaN or infinity, a value outside its
    range, an unknown choice."""


class InputTypeError(InputError, TypeError):
    """An argument of the wrong type (a string where numbers are expected, ``None``, …)."""


class ModelError(DeflexError):
    """A robot description that cannot be read or used (TOML/URDF file, schema, bounds)."""


class DataError(DeflexError):
    """A measurement file, log, G-code or in-memory table that cannot be used; the message
    names the file (or the table) and the line or row and column."""


class CalibrationError(DeflexError):
    """A calibration that cannot be done with the data given (nothing identifiable, a file
    of another robot, a bad option of the fit)."""


class CompensationError(DeflexError):
    """An offline compensation that failed, or whose points were not all compensated (no
    program is written then)."""


class ProgramError(DeflexError):
    """A robot program that cannot be written (template, names, limits)."""


class SimulationError(DeflexError):
    """The digital twin could not run (cell configuration, path, controller)."""


class DeflexIOError(DeflexError, OSError):
    """A file or folder could not be written."""


class InternalError(DeflexError):
    """A bug in deflex (a Rust panic caught at the boundary): please report it."""
