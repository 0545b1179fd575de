"""Seeded mutations of a reader's seed file, each with what reading it must do.

- ``refuse``: invalid by construction (a bool, a quoted string, 4_00, 1e308 or NaN where a
  number goes; a key no reader knows; a count that disagrees with the data; a NUL in a file
  name; a second units line): an ArmkitError naming the file. Reading it is a silent accept.
- ``same``: a change that keeps the content (comments, keys reordered, another YAML layout,
  another PCD layout of the same points): it must read to the same digest as the seed.
- ``either``: random damage (bytes flipped, cut, repeated; lines deleted or doubled; a value of
  another type): an ArmkitError naming the file, or a result (whatever it holds).
"""

from __future__ import annotations

import copy
import random
import struct
from dataclasses import dataclass
from pathlib import Path

import yaml

from tests.fuzz.seeds import READERS, write_seed, yaml_text


@dataclass
class Case:
    reader: str
    path: str
    expect: str                  # "refuse", "same" or "either"
    mutation: str
    reference: str | None = None  # "same": the seed file


BAD_NUMBERS = [True, False, "1.5", "4_00", "0", 1e308, -1e308, float("nan"), float("inf"),
               10**400, [1, 2], {"a": 1}]
BAD_TOKENS = ["nan", "inf", "1_0", "0x10", "true", "1e308", "²", "", "1,5", "1e", "--1",
              "١", "1" * 5000]
PATH_KEYS = ("robot", "file", "map", "scene", "cloud", "urdf")
# Where a NaN token is a point without a return (dropped and counted), not an error.
NAN_IS_DATA = ("cloud_csv", "pcd_ascii", "ply_ascii")


def _leaves(node, path=()):
    """(path, value) of every scalar in a YAML document."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _leaves(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _leaves(v, path + (i,))
    else:
        yield path, node


def _set(document, path, value):
    node = document
    for part in path[:-1]:
        node = node[part]
    node[path[-1]] = value


def _damage(raw: bytes, rng: random.Random) -> tuple[bytes, str]:
    """Random damage to any file's bytes."""
    kind = rng.choice(["flip", "cut", "repeat", "insert", "zero"])
    if not raw:
        return b"\xff", "empty -> a byte"
    i = rng.randrange(len(raw))
    if kind == "flip":
        k = rng.randint(1, 8)
        data = bytearray(raw)
        for _ in range(k):
            data[rng.randrange(len(data))] = rng.randrange(256)
        return bytes(data), f"{k} bytes flipped"
    if kind == "cut":
        return raw[:i], f"cut at {i}"
    if kind == "repeat":
        j = min(len(raw), i + rng.randint(1, 200))
        return raw[:j] + raw[i:j] + raw[j:], f"bytes {i}..{j} repeated"
    if kind == "insert":
        return raw[:i] + bytes(rng.randrange(256) for _ in range(rng.randint(1, 20))) + raw[i:], \
            f"bytes inserted at {i}"
    return raw[:i] + bytes(min(64, len(raw) - i)) + raw[i + 64:], f"zeros at {i}"


def _lines_damage(text: str, rng: random.Random) -> tuple[str, str]:
    lines = text.splitlines()
    i = rng.randrange(len(lines))
    kind = rng.choice(["delete", "double", "swap"])
    if kind == "delete":
        return "\n".join(lines[:i] + lines[i + 1:]) + "\n", f"line {i + 1} deleted"
    if kind == "double":
        return "\n".join(lines[:i + 1] + lines[i:]) + "\n", f"line {i + 1} doubled"
    j = rng.randrange(len(lines))
    lines[i], lines[j] = lines[j], lines[i]
    return "\n".join(lines) + "\n", f"lines {i + 1} and {j + 1} swapped"


def _random_damage(raw: bytes, rng: random.Random, lines: float) -> tuple[bytes, str, str]:
    """Lines deleted, doubled or swapped (`lines` > 0), else bytes damaged: "either"."""
    if lines > 0:
        text, what = _lines_damage(raw.decode(), rng)
        return text.encode(), "either", what
    data, what = _damage(raw, rng)
    return data, "either", what


def _yaml_case(reader: str, raw: bytes, rng: random.Random) -> tuple[bytes, str, str]:
    document = yaml.safe_load(raw.decode())
    leaves = list(_leaves(document))
    numbers = [(p, v) for p, v in leaves if isinstance(v, (int, float)) and not isinstance(v, bool)]
    paths = [(p, v) for p, v in leaves if isinstance(v, str) and p and p[-1] in PATH_KEYS]
    roll = rng.random()
    if roll < 0.45 and numbers:
        path, _ = rng.choice(numbers)
        bad = rng.choice(BAD_NUMBERS)
        mutated = copy.deepcopy(document)
        _set(mutated, path, bad)
        text = yaml_text(mutated)
        if isinstance(bad, str):            # a string that looks like a number: quoted
            text = text.replace(f"'{bad}'", f'"{bad}"')
        if bad == "4_00":                   # and unquoted, as YAML 1.1 reads as 400
            text = text.replace('"4_00"', "4_00")
        return text.encode(), "refuse", f"{'.'.join(map(str, path))} = {bad!r:.40}"
    if roll < 0.52 and paths:
        path, value = rng.choice(paths)
        mutated = copy.deepcopy(document)
        bad = rng.choice([value + "\0x", "x" * 300, "\0"])
        _set(mutated, path, bad)
        return yaml_text(mutated).encode(), "refuse", f"{'.'.join(map(str, path))}: bad name"
    if roll < 0.60:
        mutated = copy.deepcopy(document)
        nodes = [p for p, _ in leaves if len(p) > 1 and isinstance(p[-2], str)] or [()]
        target = rng.choice(nodes)[:-1]
        node = mutated
        for part in target:
            node = node[part]
        if isinstance(node, dict):
            node["no_such_field"] = 1
            return yaml_text(mutated).encode(), "refuse", "unknown field"
        return yaml_text(mutated).encode(), "either", "unchanged dump"
    if roll < 0.70:
        # The same document another way: comments, flow style, keys reordered at the top.
        mutated = dict(document) if isinstance(document, dict) else document
        if isinstance(mutated, dict) and rng.random() < 0.5:
            keys = list(mutated)
            rng.shuffle(keys)
            mutated = {k: mutated[k] for k in keys}
        style = rng.choice([True, False, None])
        text = yaml.safe_dump(mutated, sort_keys=False, default_flow_style=style, width=1000)
        text = "# a comment\n" + text.replace("\n", "  # note\n", 1)
        return text.encode(), "same", f"layout (flow {style}) and comments"
    if roll < 0.80 and numbers:
        path, _ = rng.choice(numbers)
        mutated = copy.deepcopy(document)
        _set(mutated, path, rng.choice(["text", None, [], {}, -1, 0, 1e6, -0.0]))
        return yaml_text(mutated).encode(), "either", f"{'.'.join(map(str, path))} replaced"
    return _random_damage(raw, rng, 0.88 - roll)


def _csv_case(reader: str, raw: bytes, rng: random.Random) -> tuple[bytes, str, str]:
    text = raw.decode()
    lines = text.splitlines()
    data_rows = [i for i, ln in enumerate(lines) if ln and not ln.startswith("#")][1:]
    roll = rng.random()
    if roll < 0.45 and data_rows:
        i = rng.choice(data_rows)
        cells = lines[i].split(",")
        j = rng.randrange(len(cells))
        token = rng.choice(BAD_TOKENS)
        cells[j] = token
        lines[i] = ",".join(cells)
        expect = "refuse"
        if token in ("nan", "inf") and reader in NAN_IS_DATA:
            expect = "either"
        if token == "1,5" or token == "":     # one cell becomes two, or empty: refused too
            expect = "refuse"
        return ("\n".join(lines) + "\n").encode(), expect, f"line {i + 1} cell {j}: {token!r:.20}"
    if roll < 0.55 and reader in ("measurements", "accuracy", "cloud_csv"):
        units = [i for i, ln in enumerate(lines) if "units" in ln]
        if units:
            other = "# units: m deg" if reader == "measurements" else "# units: m"
            lines.insert(units[0] + 1, other)
            return ("\n".join(lines) + "\n").encode(), "refuse", "a second units line"
    if roll < 0.65 and data_rows:
        i = rng.choice(data_rows)
        lines[i] = lines[i] + ",1"
        return ("\n".join(lines) + "\n").encode(), "refuse", f"line {i + 1}: a value more"
    if roll < 0.72 and reader != "waypoints_csv":
        at = rng.choice([i for i, ln in enumerate(lines) if ln.startswith("#")] or [0])
        lines.insert(at, "# a comment")
        lines.insert(len(lines), "")
        return ("\n".join(lines) + "\n").encode(), "same", "a comment and a blank line"
    return _random_damage(raw, rng, 0.85 - roll)


def _replace_header(raw: bytes, key: bytes, value: bytes) -> bytes:
    start = raw.index(b"\n" + key + b" ") + 1
    end = raw.index(b"\n", start)
    return raw[:start] + key + b" " + value + raw[end:]


def _pcd_case(reader: str, raw: bytes, rng: random.Random) -> tuple[bytes, str, str]:
    body_at = raw.index(b"\nDATA ") + 1
    body_at = raw.index(b"\n", body_at) + 1
    n = int(raw.split(b"\nPOINTS ")[1].split(b"\n")[0])
    roll = rng.random()
    if roll < 0.45:
        kind = rng.randrange(11)
        if kind == 0:
            return _replace_header(raw, b"POINTS", rng.choice([b"-1", b"0", str(n + 1).encode(),
                                                               b"1e3", b"\xc2\xb2"])), \
                "refuse", "POINTS"
        if kind == 1:
            return _replace_header(raw, b"COUNT", rng.choice([b"0 1 1 1", b"-1 1 1 1",
                                                              b"99999999999 1 1 1",
                                                              b"1 1 1"])), "refuse", "COUNT"
        if kind == 2:
            return _replace_header(raw, b"WIDTH", str(n + rng.randint(1, 5)).encode()), \
                "refuse", "WIDTH"
        if kind == 3:
            return _replace_header(raw, b"SIZE", rng.choice([b"4 4 3 4", b"4 4 4", b"16 4 4 4"])), \
                "refuse", "SIZE"
        if kind == 4:
            return _replace_header(raw, b"FIELDS", rng.choice([b"x y y intensity",
                                                               b"x y intensity z2"])), \
                "refuse", "FIELDS"
        if kind == 5:            # a cut text body may still be numbers: refused only in binary
            return raw[:-rng.randint(1, 40)], "either" if reader == "pcd_ascii" else "refuse", \
                "body cut"
        if kind == 6:            # bytes after the data: text may read them as more numbers
            return raw + bytes([rng.randint(1, 255)]) * rng.randint(1, 40), \
                "either" if reader == "pcd_ascii" else "refuse", "bytes after the body"
        if kind == 7 and reader == "pcd_compressed":
            packed, unpacked = struct.unpack_from("<II", raw, body_at)
            lie = rng.choice([(packed, unpacked + 4), (packed, unpacked * 1000),
                              (packed + 7, unpacked), (max(packed - 7, 0), unpacked)])
            return raw[:body_at] + struct.pack("<II", *lie) + raw[body_at + 8:], "refuse", \
                f"sizes {lie}"
        if kind == 8 and reader == "pcd_ascii":
            lines = raw[body_at:].split(b"\n")
            i = rng.randrange(n)
            cells = lines[i].split(b" ")
            cells[rng.randrange(len(cells))] = rng.choice([b"1_0", b"0x10", b"true", b"\xc2\xb2",
                                                            b"1e400e", b"1,5"])
            lines[i] = b" ".join(cells)
            return raw[:body_at] + b"\n".join(lines), "refuse", "a bad number"
        if kind == 9:
            return _replace_header(raw, b"DATA", rng.choice([b"binary_zipped", b"text", b""])), \
                "refuse", "DATA"
        if kind == 10:
            return raw.replace(b"# units: mm", b"# units: mm\n# units: m"), "refuse", \
                "two units"
        return _replace_header(raw, b"TYPE", b"X F F F"), "refuse", "TYPE"
    if roll < 0.55:
        from armkit.io.clouds import read_cloud, write_pcd
        import tempfile
        with tempfile.TemporaryDirectory() as scratch:
            source = Path(scratch) / "s.pcd"
            source.write_bytes(raw)
            cloud = read_cloud(source)
            data = rng.choice(["ascii", "binary", "binary_compressed"])
            out = write_pcd(Path(scratch) / "o.pcd", cloud.points, "mm", data=data,
                            fields=dict(cloud.fields))
            return out.read_bytes(), "same", f"rewritten as {data}"
    if roll < 0.62:
        return raw.replace(b"VERSION", b"# another comment\nVERSION", 1), "same", "a comment"
    data, what = _damage(raw, rng) if rng.random() < 0.5 else (
        raw[:body_at] + _damage(raw[body_at:], rng)[0], "body damaged")
    return data, "either", what


def _ply_case(reader: str, raw: bytes, rng: random.Random) -> tuple[bytes, str, str]:
    roll = rng.random()
    if roll < 0.45:
        kind = rng.randrange(6)
        if kind == 0:
            return raw.replace(b"element vertex 300", rng.choice([b"element vertex -5",
                                                                   b"element vertex 301",
                                                                   b"element vertex 3e2"])), \
                "refuse", "vertex count"
        if kind == 1:
            return raw.replace(b"element face 2", b"element face -1"), "refuse", "face count"
        if kind == 2:
            return raw.replace(b"property float y\n", b"property float y\nproperty float y\n"), \
                "refuse", "property twice"
        if kind == 3:
            return raw + b"\x01\x02", "refuse", "bytes after the body"
        if kind == 4:
            return raw[:-rng.randint(1, 30)], "either" if reader == "ply_ascii" else "refuse", \
                "body cut"
        return raw.replace(b"format ", b"format binary_middle_endian 1.0\ncomment ", 1), \
            "refuse", "format"
    if roll < 0.55:
        return raw.replace(b"comment units mm", b"comment units mm\ncomment scanned today"), \
            "same", "a comment"
    data, what = _damage(raw, rng)
    return data, "either", what


def _lines_case(reader: str, raw: bytes, rng: random.Random) -> tuple[bytes, str, str]:
    """MoveIt .scene files."""
    lines = raw.decode().splitlines()
    numeric = [i for i, ln in enumerate(lines) if ln and all(
        c in "0123456789.- " for c in ln)]
    roll = rng.random()
    if roll < 0.5:
        i = rng.choice(numeric)
        words = lines[i].split()
        j = rng.randrange(len(words))
        words[j] = rng.choice(["²", "1" * 5000, "1e308", "nan", "inf", "0x1", "1_0", "true",
                               "-", "1.5.5"])
        lines[i] = " ".join(words)
        return ("\n".join(lines) + "\n").encode(), "refuse", f"line {i + 1}: {words[j]!r:.20}"
    if roll < 0.6:
        i = rng.choice(numeric)
        lines[i] = lines[i] + " 1"
        return ("\n".join(lines) + "\n").encode(), "refuse", f"line {i + 1}: a number more"
    return _random_damage(raw, rng, 0.8 - roll)


def _json_case(reader: str, raw: bytes, rng: random.Random) -> tuple[bytes, str, str]:
    import json
    document = json.loads(raw)
    roll = rng.random()
    if roll < 0.5:
        q = copy.deepcopy(document)
        i, j = rng.randrange(len(q["q"])), rng.randrange(6)
        bad = rng.choice([True, "1", None, float("nan"), float("inf"), 1e308, [1], {"a": 1}])
        q["q"][i][j] = bad
        return json.dumps(q).encode(), "refuse", f"q[{i}][{j}] = {bad!r}"
    if roll < 0.6:
        return json.dumps(document, indent=2).encode(), "same", "indented"
    data, what = _damage(raw, rng)
    return data, "either", what


FAMILIES = {"yaml": _yaml_case, "csv": _csv_case, "pcd": _pcd_case, "ply": _ply_case,
            "lines": _lines_case, "json": _json_case}


def generate(reader: str, count: int, seed: int, folder: Path) -> list[Case]:
    """`count` mutated files of reader `reader`, written under `folder`."""
    rng = random.Random(f"{reader}-{seed}")
    base = folder / reader
    reference = write_seed(reader, base)
    raw = reference.read_bytes()
    family = READERS[reader][2]
    cases = []
    for k in range(count):
        data, expect, what = FAMILIES[family](reader, raw, rng)
        path = base / f"m{k:05d}{reference.suffix}" if reader not in ("task", "plan", "scene") \
            else base / f"m{k:05d}.yaml"
        path.write_bytes(data)
        cases.append(Case(reader, str(path), expect, what, str(reference)))
    return cases

