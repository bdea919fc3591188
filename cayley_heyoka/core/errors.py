"""Exceptions raised for bad input and for integrations that cannot go on."""

from __future__ import annotations

from typing import Any


class SceneError(ValueError):
    """A scene field violates a constraint.

    Parameters
    ----------
    field
        Dotted path of the offending field, e.g. ``"body.inertia"``.
    constraint
        What the field must satisfy, and what it was.
    """

    def __init__(self, field: str, constraint: str) -> None:
        self.field = field
        self.constraint = constraint
        super().__init__(f"{field}: {constraint}")


class OptionError(SceneError):
    """An option that sets a scene field (a command-line option such as ``--tolerance``, or a
    keyword argument such as ``tolerance``) violates that field's constraint: named by the
    option, not by the scene's field, which the scene's file does not hold.

    ``str()`` reads ``--tolerance must be < 1 …``; :attr:`field` is the option's name.
    """

    def __str__(self) -> str:
        return f"{self.field} {self.constraint}"


class IntegrationError(RuntimeError):
    """An integration stopped before the last output time.

    The results computed before the failure are kept in :attr:`result` (a
    :class:`~cayley_heyoka.core.result.Result`; typed loosely here, since results are built
    on these errors' module and not the other way round).
    """

    def __init__(self, message: str, result: Any) -> None:
        self.result = result
        super().__init__(message)


class Interrupted(KeyboardInterrupt):
    """A run ended by Ctrl-C (or SIGTERM turned into one): what was computed is in
    :attr:`result`, whose status says so.

    A KeyboardInterrupt, not an :class:`IntegrationError`: code that tolerates one failed run
    among many (a sweep) must still stop on Ctrl-C.
    """

    def __init__(self, message: str, result: Any) -> None:
        self.result = result
        super().__init__(message)
