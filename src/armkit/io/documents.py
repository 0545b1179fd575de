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


def _strict_number(value: Any) -> float:
    """A finite int or float as a float; a bool, a string or anything else is refused."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"expected a valid number, found {found_text(value)}")
    try:
        number = float(value)
    except OverflowError:                     # an int beyond the largest double
        number = math.inf
    if not math.isfinite(number):
        raise ValueError(f"expected a finite number, found {found_text(value)}")
    return number


Number = Annotated[float, BeforeValidator(_strict_number)]
"""A file's number field: a finite int or float (``true`` or ``"1.5"`` is not a number)."""


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


# YAML 1.1 (PyYAML) reads 1e-3 as a string, as it wants a dot in a float; YAML 1.2 and every
# user reads it as a number, and so does armkit.
_UniqueKeyLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$"),
    list("-+.0123456789"))


def read_bytes(path: str | Path, max_bytes: int = MAX_BYTES) -> bytes:
    """A regular file's bytes, at most `max_bytes`; anything else is a ModelFileError.

    A device or a pipe (``/dev/zero``, a FIFO) is refused before it is opened, and a file is
    never read past its bound, so no file can make this hang or fill the memory.
    """
    path = Path(path)
    try:
        if path.exists() and not path.is_file():
            raise ModelFileError(str(path), "", "a regular file", "a directory, device or pipe")
        with path.open("rb") as stream:
            data = stream.read(max_bytes + 1)
    except OSError as err:
        raise ModelFileError(str(path), "", "a readable file", err.strerror or str(err)) from None
    if len(data) > max_bytes:
        raise ModelFileError(str(path), "", f"a file of at most {max_bytes} bytes",
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
    if isinstance(value, str):
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
