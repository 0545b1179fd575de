"""The YAML and text helpers every reader uses: bounded, strict, one precise error."""

from __future__ import annotations


import pytest
from pydantic import ValidationError

from armkit.errors import ModelFileError
from armkit.io.documents import (MAX_DEPTH, Number, StrictModel, found_text, kind_of,
                                 read_bytes, read_text, read_yaml, validation_error)


def write(tmp_path, text: str | bytes, name: str = "doc.yaml"):
    path = tmp_path / name
    (path.write_bytes if isinstance(text, bytes) else path.write_text)(text)
    return path


@pytest.mark.parametrize("text, words", [
    ("a: &x [1, 2]\nb: *x\n", "line 2: expected valid YAML, found an alias (*x)"),
    ("a: [1, {<<: *base}]\n", "found an alias (*base)"),
    ("a: " + "[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1) + "\n",
     f"found nesting deeper than {MAX_DEPTH} levels"),
    ("a: " + "{b: " * 2000 + "1" + "}" * 2000 + "\n", "found nesting deeper than"),
    ("a: " + "9" * 5000 + "\n", "expected valid YAML, found Exceeds the limit"),
    ("a: 2001-13-45\n", "expected valid YAML, found month must be in 1..12"),
    ("a: !!python/object:os.system ls\n", "expected valid YAML, found could not determine"),
    ("a: 1\na: 2\n", "key 'a' given twice"),
    ("a: 1\nb: \x00\n", "line 2: expected valid YAML, found unacceptable character U+0000: "
     "special characters are not allowed"),
])
def test_hostile_yaml_is_one_precise_error(tmp_path, text, words):
    path = write(tmp_path, text)
    with pytest.raises(ModelFileError) as err:
        read_yaml(path)
    assert str(err.value).startswith(f"{path}: ") and words in str(err.value), str(err.value)
    assert len(str(err.value)) < len(str(path)) + 200 and "\n" not in str(err.value)


def test_nesting_up_to_the_bound_is_read(tmp_path):
    depth = MAX_DEPTH - 1
    assert read_yaml(write(tmp_path, "[" * depth + "]" * depth)) is not None


def test_size_bound_and_special_files(tmp_path):
    path = write(tmp_path, "a: 1\n" * 100)
    assert read_text(path, max_bytes=500) == "a: 1\n" * 100
    with pytest.raises(ModelFileError, match="expected a file of at most 499 bytes, found a "
                                             "larger one"):
        read_yaml(path, max_bytes=499)
    with pytest.raises(ModelFileError, match="expected a regular file, found a directory"):
        read_bytes(tmp_path)
    with pytest.raises(ModelFileError, match="/dev/zero: expected a regular file"):
        read_text("/dev/zero")                  # refused before reading: never a hang
    with pytest.raises(ModelFileError, match="expected a readable file"):
        read_text(tmp_path / "missing.yaml")


def test_found_text_bounds_its_work():
    nested: list = []
    for _ in range(20_000):                      # repr() of this raises RecursionError
        nested = [nested]
    cases = [list(range(10**6)), dict.fromkeys(range(10**5)), "x" * 10**7,
             10**20000, nested, b"\x00" * 10**6, object()]
    texts = [found_text(value) for value in cases]
    assert all(len(t) <= 60 for t in texts), texts
    taken = []

    class Counted(list):
        """A list that counts the items read from it."""

        def __iter__(self):
            for item in super().__iter__():
                taken.append(item)
                yield item

    assert "0, 1, 2, " in found_text(Counted(range(10**6)))
    assert len(taken) < 60, "found_text read items in proportion to the value"
    assert texts[0].startswith("[0, 1, 2, ") and texts[0].endswith("...")
    assert texts[3] == "an integer of about 20000 digits"
    assert texts[4].startswith("[[[[") and texts[6] == "a object"
    assert found_text([1.5, True, None, "a"]) == "[1.5, True, None, 'a']"


class Doc(StrictModel):
    x: Number
    xs: list[Number] = []


@pytest.mark.parametrize("value, words", [
    (True, "x: expected a valid number, found True"),
    ("1.5", "x: expected a valid number, found '1.5'"),
    (float("nan"), "x: expected a finite number, found nan"),
    (10**400, "x: expected a finite number, found an integer of about 400 digits"),
    ([1], "x: expected a valid number, found [1]"),
])
def test_number_is_strict_and_finite(value, words):
    with pytest.raises(ValidationError) as err:
        Doc.model_validate({"x": value})
    message = str(validation_error("f.yaml", err.value, Doc))
    assert message == f"f.yaml: {words}", message


def test_number_takes_ints_and_floats():
    assert Doc.model_validate({"x": 3, "xs": [1, 2.5, -0.0]}).xs == [1.0, 2.5, 0.0]
    assert isinstance(Doc.model_validate({"x": 3}).x, float)


def test_kind_of():
    assert kind_of(None) == "nothing (an empty document)"
    assert kind_of([1]) == "a list" and kind_of(1) == "an int"
