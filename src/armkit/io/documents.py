"""YAML documents with precise errors: the one way armkit reads a text or YAML file.

Every reader in armkit (robot files, register maps, waypoint files, trajectory cases, scenes,
tasks) goes through these helpers, so a mistake is always one `ModelFileError` naming the file,
the field path, what was expected and what was found.
"""

from __future__ import annotations

import difflib
from collections.abc import Hashable
from pathlib import Path
from typing import Any, get_args

import yaml
from pydantic import BaseModel, ConfigDict, ValidationError

from armkit.errors import ModelFileError


class StrictModel(BaseModel):
    """Base of armkit's file models: an unknown field is a mistake, not something to ignore,
    and so is NaN or inf (``.nan``, ``.inf`` in YAML) where a number is expected."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)



class _UniqueKeyLoader(yaml.SafeLoader):
    """safe_load that refuses a key given twice in one mapping (PyYAML keeps the last)."""

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if not isinstance(key, Hashable):
                raise yaml.constructor.ConstructorError(
                    None, None, f"a key that is a {type(key).__name__}", key_node.start_mark)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"key {key!r} given twice", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


def read_text(path: str | Path) -> str:
    """A UTF-8 text file's contents; a missing or undecodable file is a ModelFileError."""
    try:
        return Path(path).read_text(encoding="utf-8")
    except OSError as err:
        raise ModelFileError(str(path), "", "a readable file", err.strerror or str(err)) from None
    except UnicodeDecodeError as err:
        raise ModelFileError(str(path), "", "a UTF-8 text file",
                             f"byte {err.object[err.start]:#04x} at offset {err.start}") from None


def read_yaml(path: str | Path) -> Any:
    """Parse a YAML file safely; any failure is a ModelFileError naming the line."""
    text = read_text(path)
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark else ""
        problem = getattr(err, "problem", None) or str(err)
        raise ModelFileError(str(path), where, "valid YAML", problem) from None


def _field_path(loc: tuple) -> str:
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def found_text(value: Any) -> str:
    """A value as an error message shows it: its repr, cut at 60 characters."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def validation_error(path: str, err: ValidationError, model: type[BaseModel]) -> ModelFileError:
    """The first error of a pydantic ValidationError as one precise ModelFileError."""
    first = err.errors()[0]
    loc, kind, msg = tuple(first["loc"]), first["type"], first["msg"]
    if kind == "missing":
        return ModelFileError(path, _field_path(loc), "a value", "nothing")
    if kind == "too_short":
        return ModelFileError(path, _field_path(loc), f"at least {first['ctx']['min_length']} "
                              f"item(s)", f"{first['ctx']['actual_length']}")
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
