"""YAML documents with precise errors: the one way armkit reads a text or YAML file.

Every reader in armkit (robot files, register maps, waypoint files, trajectory cases, scenes,
tasks) goes through these helpers, so a mistake is always one `ModelFileError` naming the file,
the field path, what was expected and what was found.
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Hashable
from pathlib import Path
from typing import Annotated, Any, Literal, get_args

import yaml
from pydantic import BaseModel, BeforeValidator, ConfigDict, ValidationError

from armkit.errors import ModelFileError


class StrictModel(BaseModel):
    """Base of armkit's file models: an unknown field is a mistake, not something to ignore,
    and so is NaN or inf (``.nan``, ``.inf`` in YAML) where a number is expected."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


LARGEST = 1e9
"""The largest magnitude of a number in any file, in the file's own units (1e9 mm is 1000 km;
squares and sums of such numbers stay far from overflow). The command line's rule too."""

_DECIMAL = re.compile(r"[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?")
_INTEGER = re.compile(r"[-+]?[0-9]+")


def _span(low: float, high: float, low_open: bool) -> str:
    if not (math.isfinite(low) or math.isfinite(high)):
        return ""
    return (f" above {low:g} and at most {high:g}" if low_open else f" from {low:g} to {high:g}")


def check_number(value: Any, low: float = -LARGEST, high: float = LARGEST, *,
                 low_open: bool = False, integer: bool = False) -> float | int:
    """The one rule for a number read from a file (YAML value, CSV cell, header word).

    A number is an int or a float (a bool is not), or, in a text format, a plain ASCII decimal
    (``-1.5``, ``2e-3``; not ``0x10``, ``4_00``, ``nan``, ``inf``, ``²`` or ``"1.5"`` quoted in
    YAML); it is finite and within ``[low, high]`` (``(low, high]`` with `low_open`), at most
    `LARGEST` in magnitude unless the field states a range of its own; an integer field takes
    whole numbers only (not 3.0).

    Parameters
    ----------
    value : int, float or str
        A str only from a text format's cell (a YAML string is refused by `Number`).

    Returns
    -------
    float, or int when `integer`

    Raises
    ------
    ValueError
        ``expected a number from -1e+09 to 1e+09, found 1e+308``, the message that
        `validation_error` and `number_from_text` turn into a ModelFileError.
    """
    what = "a whole number" if integer else "a valid number"
    span = _span(low, high, low_open)
    if isinstance(value, str):
        text = value.strip()
        if not (_INTEGER if integer else _DECIMAL).fullmatch(text) or len(text) > 400:
            raise ValueError(f"expected {what}{span}, found {found_text(value)}")
        value = int(text) if integer else float(text)
    elif isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"expected {what}{span}, found {found_text(value)}")
    if integer and isinstance(value, float):
        raise ValueError(f"expected {what}{span}, found {found_text(value)}")
    try:
        number = float(value)
    except OverflowError:                     # an int beyond the largest double
        number = math.inf
    if not math.isfinite(number):
        raise ValueError(f"expected a finite number{span}, found {found_text(value)}")
    if number < low or number > high or (low_open and number == low):
        raise ValueError(f"expected {what.replace('a valid', 'a')}{span}, found {number:g}")
    return int(value) if integer else number


def number_from_text(text: str, path: str, field: str, low: float = -LARGEST,
                     high: float = LARGEST, **kwargs) -> float | int:
    """`check_number` for a word of a text file; a bad one is a ModelFileError naming `field`."""
    try:
        return check_number(text, low, high, **kwargs)
    except ValueError as err:
        expected, _, found = str(err).removeprefix("expected ").partition(", found ")
        raise ModelFileError(path, field, expected, found) from None


def bounded(low: float = -LARGEST, high: float = LARGEST, *, low_open: bool = False,
            integer: bool = False) -> Any:
    """A pydantic field type for a file's number within a stated range (see `check_number`)."""
    def check(value: Any) -> float | int:
        if isinstance(value, str):            # a quoted "1.5" in YAML is text, not a number
            what = "a whole number" if integer else "a valid number"
            raise ValueError(f"expected {what}{_span(low, high, low_open)}, found "
                             f"{found_text(value)}")
        return check_number(value, low, high, low_open=low_open, integer=integer)

    return Annotated[int if integer else float, BeforeValidator(check)]


Number = bounded(-math.inf, math.inf)
"""A file's number field: a finite int or float (``true`` or ``"1.5"`` is not a number); the
robot loader states each field's range after converting it to SI."""

Value = bounded()
"""A file's number field in the file's units: a finite int or float of magnitude at most
`LARGEST` (``true``, ``"1.5"`` and ``1e308`` are not)."""

Positive = bounded(0.0, LARGEST, low_open=True)
"""A length, radius or time that must be above zero (file units)."""

Fraction = bounded(0.0, 1.0)
"""A number from 0 to 1."""


SEED = (0, 2**32 - 1)
"""A random seed's range, in files and on the command line (32 bits, as most tools take)."""


def whole(low: int, high: int) -> Any:
    """A whole-number field from `low` to `high` (``true``, ``1.0`` and ``"3"`` are not)."""
    return bounded(low, high, integer=True)


def is_number(text: str) -> bool:
    """Whether Python reads `text` as a float ("1e-3", "nan" and "-inf" are numbers)."""
    try:
        float(text)
    except ValueError:
        return False
    return True


class UnitsField(StrictModel):
    """A file's declared units: ``units: {length: mm, angle: deg}``."""

    length: Literal["mm", "m"]
    angle: Literal["deg", "rad"]

MAX_BYTES = 8 * 2**20
"""The largest file read_text and read_yaml read by default (bytes)."""

MAX_DEPTH = 64
"""The deepest nesting of lists and mappings read_yaml accepts."""


class _UniqueKeyLoader(yaml.SafeLoader):
    """safe_load that refuses a key given twice in one mapping (PyYAML keeps the last), any
    alias (so a few hundred bytes cannot expand to gigabytes: "billion laughs"), and nesting
    deeper than MAX_DEPTH (so it cannot exhaust the stack)."""

    depth = 0

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            raise yaml.composer.ComposerError(
                None, None, f"an alias (*{str(event.anchor)[:40]}); anchors and aliases are "
                "not supported", event.start_mark)
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise yaml.composer.ComposerError(
                None, None, f"nesting deeper than {MAX_DEPTH} levels", self.peek_event().start_mark)
        try:
            return super().compose_node(parent, index)
        finally:
            self.depth -= 1

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if not isinstance(key, Hashable):
                raise yaml.constructor.ConstructorError(
                    None, None, f"a key that is a {type(key).__name__}", key_node.start_mark)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"key {found_text(key)} given twice", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


# Numbers as YAML 1.2 reads them, not YAML 1.1 (PyYAML's): 1.1 reads 1e-3 as a string (it
# wants a dot in a float), and 4_00 as 400, 1:30 as 90 (base 60), 0b11 as 3 and 017 as 15; a
# user who types 1:30 or 017 means neither. Under 1.2 those are strings, which a number field
# refuses by name. Decimal, 0x and 0o integers, and floats with or without a dot, are numbers.
_UniqueKeyLoader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers
            if tag not in ("tag:yaml.org,2002:int", "tag:yaml.org,2002:float")]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()}
_UniqueKeyLoader.add_implicit_resolver(
    "tag:yaml.org,2002:int", re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$"),
    list("-+0123456789"))
_UniqueKeyLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
               r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"),
    list("-+.0123456789"))


def _construct_int(loader, node):
    # PyYAML's int constructor reads 0o17 as 0o17's digits in base 8 only without the "o".
    text = loader.construct_scalar(node)
    sign = -1 if text.startswith("-") else 1
    text = text.lstrip("+-")
    base = 16 if text.startswith("0x") else 8 if text.startswith("0o") else 10
    return sign * int(text[2:] if base != 10 else text, base)


_UniqueKeyLoader.add_constructor("tag:yaml.org,2002:int", _construct_int)


LONGEST_NAME = 255
"""Characters of one file name (NAME_MAX on Linux, macOS, NTFS)."""

LONGEST_PATH = 4096
"""Characters of a whole path (PATH_MAX on Linux)."""


def checked_path(text: str | Path, source: str = "", field: str = "",
                 folder: str | Path | None = None) -> Path:
    """The one path rule: a path a file names (or a user types), checked before it is used.

    No NUL character, no name longer than `LONGEST_NAME` characters, at most `LONGEST_PATH`
    in all; a relative path is taken from `folder` (for a file that names another file: the
    naming file's own folder, so that a task or scene moves with the files beside it) or
    else from the working directory. Whether it is a regular file is checked where it is read
    (`read_bytes`).

    Parameters
    ----------
    text : str or Path
    source, field : str
        The file that names the path and its field; empty for a path given directly (the
        message then names the path itself).
    folder : str or Path, optional

    Raises
    ------
    ModelFileError
    """
    value = str(text)
    where, what = (source, field) if source else (_cut(value, 80), "")
    longest = max((len(part) for part in re.split(r"[/\\]", value)), default=0)
    problem = ("a NUL character" if "\0" in value else
               "an empty name" if not value.strip() else
               f"a name of {longest} characters (at most {LONGEST_NAME})"
               if longest > LONGEST_NAME else
               f"a path of {len(value)} characters (at most {LONGEST_PATH})"
               if len(value) > LONGEST_PATH else None)
    if problem:
        raise ModelFileError(where, what, "a file name", problem)
    path = Path(value)
    if folder is not None and not path.is_absolute():
        path = Path(folder) / path
    return path


def read_bytes(path: str | Path, max_bytes: int = MAX_BYTES) -> bytes:
    """A regular file's bytes, at most `max_bytes`; anything else is a ModelFileError.

    The path is checked by `checked_path`; a directory, device or pipe (``/dev/zero``, a FIFO,
    a link to one) is refused before it is opened, and a file is never read past its bound, so
    no file can make this hang or fill the memory.
    """
    path = checked_path(path)
    name = str(path)
    try:
        if path.exists() and not path.is_file():
            raise ModelFileError(name, "", "a regular file", "a directory, device or pipe")
        with path.open("rb") as stream:
            data = stream.read(max_bytes + 1)
    except OSError as err:
        raise ModelFileError(name, "", "a readable file", err.strerror or str(err)) from None
    if len(data) > max_bytes:
        raise ModelFileError(name, "", f"a file of at most {max_bytes} bytes",
                             "a larger one")
    return data


def read_text(path: str | Path, max_bytes: int = MAX_BYTES) -> str:
    """A UTF-8 text file's contents (at most `max_bytes`); a missing, oversized or undecodable
    file is a ModelFileError."""
    data = read_bytes(path, max_bytes)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ModelFileError(str(path), "", "a UTF-8 text file",
                             f"byte {err.object[err.start]:#04x} at offset {err.start}") from None


def read_yaml(path: str | Path, max_bytes: int = MAX_BYTES) -> Any:
    """Parse a YAML file safely; any failure is a ModelFileError naming the line.

    Refused: a key given twice in one mapping, aliases (``*name``), nesting deeper than
    MAX_DEPTH, files over `max_bytes`, and values PyYAML cannot build (an integer of more
    than 4300 digits, a date such as 2001-13-45).
    """
    text = read_text(path, max_bytes)
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)
    except yaml.reader.ReaderError as err:        # a character YAML does not allow
        line = text.count("\n", 0, err.position) + 1
        code = err.character if isinstance(err.character, int) else ord(err.character[:1] or " ")
        raise ModelFileError(str(path), f"line {line}", "valid YAML",
                             f"unacceptable character U+{code:04X}: {err.reason}") from None
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark else ""
        problem = " ".join(str(getattr(err, "problem", None) or err).split())
        raise ModelFileError(str(path), where, "valid YAML", _cut(problem, 120)) from None
    except (ValueError, OverflowError, TypeError, RecursionError) as err:
        # Raised by PyYAML's constructors for values it parses but cannot build.
        raise ModelFileError(str(path), "", "valid YAML",
                             _cut(" ".join(str(err).split()), 120)) from None


def kind_of(value: Any) -> str:
    """What a parsed document holds, in words: ``nothing (an empty document)``, ``a list``..."""
    if value is None:
        return "nothing (an empty document)"
    name = type(value).__name__
    return f"a {name}" if name[0] not in "aeiou" else f"an {name}"


def _field_path(loc: tuple) -> str:
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


FOUND_CHARS = 60
"""The longest rendering of a found value in an error message."""


def _cut(text: str, limit: int = FOUND_CHARS) -> str:
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _bounded_repr(value: Any, budget: int, depth: int = 0) -> str:
    """repr of `value` doing work in proportion to `budget` characters, not to its size.

    Containers show their first items until the budget is spent; a long string or number is
    cut before it is rendered (an int of a million digits is never converted in full).
    """
    if isinstance(value, (str, bytes)):
        return repr(value[:budget + 1])
    if isinstance(value, bool) or value is None or isinstance(value, float):
        return repr(value)
    if isinstance(value, int):
        if value.bit_length() > 4 * budget:       # more digits than the budget could show
            return f"an integer of about {int(value.bit_length() * 0.30103)} digits"
        return repr(value)
    if isinstance(value, (list, tuple, dict, set, frozenset)):
        if depth >= 8 or budget <= 0:
            return "[...]" if isinstance(value, list) else "{...}"
        opening, closing = {list: "[]", tuple: "()", dict: "{}"}.get(type(value), "{}")
        items = value.items() if isinstance(value, dict) else value
        parts, used = [], 0
        for i, item in enumerate(items):
            if used > budget:
                parts.append("...")
                break
            if isinstance(value, dict):
                part = (_bounded_repr(item[0], budget - used, depth + 1) + ": "
                        + _bounded_repr(item[1], budget - used, depth + 1))
            else:
                part = _bounded_repr(item, budget - used, depth + 1)
            parts.append(part)
            used += len(part) + 2
        return opening + ", ".join(parts) + closing
    return f"a {type(value).__name__}"


def found_text(value: Any) -> str:
    """A value as an error message shows it: its repr, cut at 60 characters.

    The work is bounded before anything is rendered, so a huge or deeply nested value costs
    no more than a small one.
    """
    return _cut(_bounded_repr(value, FOUND_CHARS))


def validation_error(path: str, err: ValidationError, model: type[BaseModel]) -> ModelFileError:
    """The first error of a pydantic ValidationError as one precise ModelFileError."""
    first = err.errors()[0]
    loc, kind, msg = tuple(first["loc"]), first["type"], first["msg"]
    if kind == "missing":
        return ModelFileError(path, _field_path(loc), "a value", "nothing")
    if kind == "too_short":
        return ModelFileError(path, _field_path(loc), f"at least {first['ctx']['min_length']} "
                              f"item(s)", f"{first['ctx']['actual_length']}")
    if kind == "too_long":
        return ModelFileError(path, _field_path(loc), f"at most {first['ctx']['max_length']} "
                              f"item(s)", str(first["ctx"].get("actual_length") or "more"))
    if kind == "extra_forbidden":
        known = _fields_at(model, loc[:-1])
        hint = difflib.get_close_matches(str(loc[-1]), known, n=1)
        expected = f"one of {', '.join(known)}" + (f" (did you mean {hint[0]!r}?)" if hint else "")
        return ModelFileError(path, _field_path(loc[:-1]) or "top level", expected,
                              f"unknown field {loc[-1]!r}")
    if msg.startswith("Value error, expected "):
        expected, _, found = msg.removeprefix("Value error, expected ").partition(", found ")
        return ModelFileError(path, _field_path(loc), expected, found or found_text(first["input"]))
    expected = msg.removeprefix("Input should be ").removeprefix("Value error, ")
    return ModelFileError(path, _field_path(loc), expected, found_text(first.get("input")))


def validated(path: str, document: Any, model: type[BaseModel]) -> BaseModel:
    """`document` validated as `model`; its first error as one ModelFileError naming `path`."""
    try:
        return model.model_validate(document)
    except ValidationError as err:
        raise validation_error(path, err, model) from None


def _fields_at(model: type[BaseModel], loc: tuple) -> list[str]:
    """Field names allowed at `loc` of a file validated by `model`, for 'did you mean'."""
    inner: type[BaseModel] | None = model
    for part in loc:
        if inner is None:
            break
        if not isinstance(part, int):            # list indices keep the list's item model
            field = inner.model_fields.get(part)
            inner = _model_in(field.annotation) if field else None
    return list(inner.model_fields) if inner else []


def _model_in(annotation: Any) -> type[BaseModel] | None:
    """The pydantic model inside an annotation such as ``list[Row]`` or ``Pose | None``."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in get_args(annotation):
        if found := _model_in(arg):
            return found
    return None
