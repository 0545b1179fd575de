"""The exceptions armkit raises: one tree under `ArmkitError`.

A failed solve or an unreachable target is not an exception but a result (see `IKResult`);
these are for misuse and bad input, with messages that say what was expected and what was found.
"""

from __future__ import annotations


MESSAGE_CHARS = 300
"""The longest message of a ModelFileError (the file, field, expected and found, cut to fit)."""


def cut(text: str, limit: int) -> str:
    """`text` if at most `limit` characters, else its start and end around "..."."""
    if len(text) <= limit:
        return text
    keep = limit - 3
    return text[:keep - keep // 3] + "..." + text[len(text) - keep // 3:]


class ArmkitError(Exception):
    """Base of every error armkit raises on purpose."""


class InputError(ArmkitError, ValueError):
    """An argument has the wrong shape, type or value.

    Message shape: ``q: expected last axis 6, found 4``.
    """


class ModelFileError(InputError):
    """A robot (or other) file is unreadable or invalid.

    Parameters
    ----------
    file : str
        The file's path as the user gave it.
    field : str
        Path of the offending field, e.g. ``joints[2].limits``; empty for the whole file.
    expected, found : str
        What the field should hold and what it holds.
    """

    def __init__(self, file: str, field: str, expected: str, found: str):
        self.file, self.field, self.expected, self.found = str(file), field, expected, found
        # At most MESSAGE_CHARS in all, however long the file's name or the value: the file
        # and the field first, then what was expected, then what was found, each cut to fit.
        name = cut(self.file, 100)
        where = f"{name}: {cut(field, 60)}" if field else name
        expected = cut(str(expected), max(MESSAGE_CHARS - len(where) - 30, 40))
        head = f"{where}: expected {expected}, found "
        super().__init__(head + cut(str(found), max(MESSAGE_CHARS - len(head), 20)))


class DriveError(ArmkitError):
    """Talking to a motor drive failed; says why and the last waypoint the drive accepted.

    Parameters
    ----------
    cause : str
        What went wrong, e.g. ``no response within 1 s x 1 attempt``.
    last_accepted : int or None
        Index (from 0) of the last waypoint the drive acknowledged; None if none was.
    waypoint : int or None
        Index of the waypoint that failed; None for a failure outside a sequence.
    outcome_unknown : bool
        True when the failed waypoint's write left but its outcome never came back (a lost
        connection or a time-out): the drive may or may not have taken it.
    """

    def __init__(self, cause: str, last_accepted: int | None = None, *,
                 waypoint: int | None = None, outcome_unknown: bool = False):
        self.cause, self.last_accepted = cause, last_accepted
        self.waypoint, self.outcome_unknown = waypoint, outcome_unknown
        last = "none" if last_accepted is None else str(last_accepted)
        where = "" if waypoint is None else f"waypoint {waypoint}: "
        unknown = (f"; whether the drive took waypoint {waypoint} is unknown"
                   if outcome_unknown and waypoint is not None else "")
        super().__init__(f"{where}{cause} (last accepted waypoint: {last}{unknown})")
