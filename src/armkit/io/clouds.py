"""Point-cloud files: PCD (ascii, binary), PLY (ascii, binary), CSV/XYZ text and NumPy .npy.

Every cloud has a length unit, m or mm: declared by the file (a comment such as ``# units: mm``
in PCD, CSV and XYZ files, ``comment units mm`` in PLY) or given by the caller; neither is an
error, and so is a caller's unit that contradicts the file's. The points come back in metres and
their scale is checked: a scene less than 5 cm across (a cloud in metres read as millimetres) or
with a median range beyond 1 km (millimetres read as metres) is refused.

Points with NaN or inf (LiDARs write them for rays with no return) are dropped and counted, or
the file is refused, as the caller chooses. Every failure is one `ModelFileError` naming the
file, the field, what was expected and what was found.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from io import StringIO
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError, ModelFileError
from armkit.io.documents import is_number

UNITS = {"m": 1.0, "mm": 1e-3}
SUFFIXES = (".pcd", ".ply", ".csv", ".xyz", ".txt", ".npy")
MIN_EXTENT = 0.05           # m: smaller scenes are taken for metres read as millimetres
MAX_RANGE = 1000.0          # m: larger median ranges are taken for millimetres read as metres
_UNIT_COMMENT = re.compile(rb"\bunits?\s*[:=]?\s*(mm|m)\b", re.IGNORECASE)


@dataclass(frozen=True)
class Cloud:
    """Points read from a file.

    Attributes
    ----------
    points : ndarray, shape (N, 3)
        Finite points, m.
    units : {"m", "mm"}
        The file's length unit.
    dropped : int
        Points with NaN or inf that were dropped.
    path : str
        The file as given.
    """

    points: NDArray
    units: str
    dropped: int
    path: str


def check_scale(points: NDArray, source: str, *, file: bool = True) -> None:
    """Refuse points (m) whose scale suggests the wrong unit.

    Parameters
    ----------
    points : ndarray, shape (N, 3), m
    source : str
        The file the points came from, or the argument's name.
    file : bool
        Whether `source` is a file (a ModelFileError) or an argument (an InputError).

    Raises
    ------
    ModelFileError or InputError
        When the middle 98 % of the points spans less than 5 cm, or their median distance from
        the sensor exceeds 1 km.
    """
    sample = points[::max(len(points) // 10_000, 1)]        # a few thousand points suffice
    lo, hi = np.percentile(sample, [1, 99], axis=0)
    extent = float(np.linalg.norm(hi - lo))
    median_range = float(np.median(np.linalg.norm(sample, axis=1)))
    problem = None
    if len(points) >= 10 and extent < MIN_EXTENT:
        problem = ("a scene at least 5 cm across (is the unit right? a cloud in metres read as "
                   "millimetres shrinks 1000 times)", f"{extent * 1e3:.3g} mm across")
    elif median_range > MAX_RANGE:
        problem = ("points within 1 km of the sensor (is the unit right? a cloud in "
                   "millimetres read as metres grows 1000 times)",
                   f"a median range of {median_range:.4g} m")
    if problem:
        if not file:
            raise InputError(f"{source}: expected {problem[0]}, found {problem[1]}")
        raise ModelFileError(source, "points", *problem)


def _declared_unit(path: str, comments: list[bytes]) -> str | None:
    """The unit a file's comments declare, if any."""
    found = {m.group(1).decode().lower() for c in comments for m in _UNIT_COMMENT.finditer(c)}
    if len(found) > 1:
        raise ModelFileError(path, "units", "one declared unit", " and ".join(sorted(found)))
    return found.pop() if found else None


def _resolve_unit(path: str, declared: str | None, given: str | None) -> str:
    if given is not None and given not in UNITS:
        raise InputError(f"units: expected m or mm, found {given!r}")
    if declared is not None and given is not None and declared != given:
        raise ModelFileError(path, "units", f"{given} as given by the caller",
                             f"the file declares {declared}")
    unit = declared or given
    if unit is None:
        raise ModelFileError(path, "units", "a length unit, m or mm, declared in the file or "
                             "given (units= or --units)", "none")
    return unit


# --- PCD ------------------------------------------------------------------------------------

_PCD_TYPES = {("F", 4): "f4", ("F", 8): "f8", ("I", 1): "i1", ("I", 2): "i2", ("I", 4): "i4",
              ("I", 8): "i8", ("U", 1): "u1", ("U", 2): "u2", ("U", 4): "u4", ("U", 8): "u8"}


def _header_lines(path: str, raw: bytes, what: str, first: tuple[bytes, ...], end) -> tuple:
    """Split an ASCII header off `raw`: (lines, offset of the data). `end(line)` ends it."""
    if not raw.lstrip().startswith(first):
        head = raw[:16]
        names = [f.decode() for f in first]
        starts = names[0] if len(names) == 1 else ", ".join(names[:-1]) + " or " + names[-1]
        raise ModelFileError(path, "", f"a {what} file (starting with {starts})",
                             "an empty file" if not raw else repr(head))
    lines, pos = [], 0
    while pos < len(raw):
        nl = raw.find(b"\n", pos)
        nl = len(raw) if nl < 0 else nl
        line = raw[pos:nl].rstrip(b"\r")
        pos = nl + 1
        lines.append(line)
        if end(line):
            return lines, pos
        if len(lines) > 200:
            break
    raise ModelFileError(path, "header", f"a {what} header ending in its data line",
                         "no end of header")


def _read_pcd(path: str, raw: bytes) -> tuple[NDArray, list[bytes]]:
    lines, start = _header_lines(path, raw, "PCD", (b"#", b"VERSION", b"FIELDS"),
                                 lambda line: line.strip().upper().startswith(b"DATA"))
    comments = [ln for ln in lines if ln.strip().startswith(b"#")]
    header = {}
    for ln in lines:
        parts = ln.split()
        if parts and not parts[0].startswith(b"#"):
            header[parts[0].decode("ascii", "replace").upper()] = [
                x.decode("ascii", "replace") for x in parts[1:]]
    fields = header.get("FIELDS")
    if not fields:
        raise ModelFileError(path, "FIELDS", "a FIELDS line naming x y z", "none")
    lower = [f.lower() for f in fields]
    missing = [c for c in "xyz" if c not in lower]
    if missing:
        raise ModelFileError(path, "FIELDS", "fields x, y and z", " ".join(fields))
    k = len(fields)
    sizes = header.get("SIZE", ["4"] * k)
    types = header.get("TYPE", ["F"] * k)
    counts = header.get("COUNT", ["1"] * k)
    for name, values in (("SIZE", sizes), ("TYPE", types), ("COUNT", counts)):
        if len(values) != k:
            raise ModelFileError(path, name, f"{k} entries, one per field", f"{len(values)}")
    try:
        sizes_i, counts_i = [int(s) for s in sizes], [int(c) for c in counts]
    except ValueError:
        raise ModelFileError(path, "SIZE/COUNT", "whole numbers",
                             " ".join(sizes + counts)) from None
    dtypes = []
    for name, t, s in zip(fields, types, sizes_i):
        if (t.upper(), s) not in _PCD_TYPES:
            raise ModelFileError(path, f"TYPE/SIZE of {name}", "F 4/8, I or U 1/2/4/8",
                                 f"{t} {s}")
        dtypes.append(_PCD_TYPES[t.upper(), s])
    try:
        if "POINTS" in header:
            n = int(header["POINTS"][0])
        else:
            n = int(header["WIDTH"][0]) * int(header.get("HEIGHT", ["1"])[0])
    except (KeyError, IndexError, ValueError):
        raise ModelFileError(path, "POINTS", "the number of points",
                             " ".join(header.get("POINTS", ["none"]))) from None
    data = header["DATA"][0].lower() if header.get("DATA") else ""
    col = {c: sum(counts_i[:lower.index(c)]) for c in "xyz"}
    if data == "ascii":
        text = raw[start:].decode("ascii", "replace")
        table = _text_table(path, text, None, first_line=len(lines) + 1)
        if table.size == 0:
            table = np.empty((0, sum(counts_i)))
        if table.shape[1] != sum(counts_i):
            raise ModelFileError(path, "DATA", f"{sum(counts_i)} values per line (FIELDS, COUNT)",
                                 f"{table.shape[1]}")
        if len(table) != n:
            raise ModelFileError(path, "POINTS", f"{n} data lines", f"{len(table)}")
        return table[:, [col["x"], col["y"], col["z"]]], comments
    if data == "binary":
        names = [f"f{i}" for i in range(k)]
        dtype = np.dtype([(nm, "<" + dt, (c,)) if c > 1 else (nm, "<" + dt)
                          for nm, dt, c in zip(names, dtypes, counts_i)])
        need = n * dtype.itemsize
        if len(raw) - start < need:
            raise ModelFileError(path, "DATA", f"{n} points of {dtype.itemsize} bytes "
                                 f"({need} bytes)", f"{len(raw) - start} bytes")
        rec = np.frombuffer(raw, dtype=dtype, count=n, offset=start)
        return np.column_stack([rec[names[lower.index(c)]].astype(float) for c in "xyz"]), \
            comments
    raise ModelFileError(path, "DATA", "ascii or binary (convert binary_compressed files "
                         "with pcl_convert_pcd_ascii_binary)", data or "nothing")


# --- PLY ------------------------------------------------------------------------------------

_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
              "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
              "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
              "float64": "f8"}


def _read_ply(path: str, raw: bytes) -> tuple[NDArray, list[bytes]]:
    lines, start = _header_lines(path, raw, "PLY", (b"ply",),
                                 lambda line: line.strip() == b"end_header")
    comments = [ln for ln in lines if ln.startswith((b"comment", b"obj_info"))]
    fmt = next((ln.split() for ln in lines if ln.startswith(b"format")), None)
    if not fmt or len(fmt) < 2:
        raise ModelFileError(path, "format", "a format line", "none")
    fmt_name = fmt[1].decode("ascii", "replace")
    order = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}
    if fmt_name not in order:
        raise ModelFileError(path, "format", "ascii, binary_little_endian or "
                             "binary_big_endian", fmt_name)
    elements: list[list] = []                       # [name, count, [(prop, type or 'list')]]
    for ln in lines:
        parts = ln.decode("ascii", "replace").split()
        if parts[:1] == ["element"] and len(parts) == 3:
            try:
                elements.append([parts[1], int(parts[2]), []])
            except ValueError:
                raise ModelFileError(path, f"element {parts[1]}", "a whole count",
                                     parts[2]) from None
        elif parts[:1] == ["property"] and elements:
            if len(parts) >= 2 and parts[1] == "list":
                elements[-1][2].append((parts[-1], "list"))
            elif len(parts) == 3 and parts[1] in _PLY_TYPES:
                elements[-1][2].append((parts[2], _PLY_TYPES[parts[1]]))
            else:
                raise ModelFileError(path, f"element {elements[-1][0]}: property",
                                     "a type such as float, double, int, uchar", " ".join(parts))
    names = [e[0] for e in elements]
    if "vertex" not in names:
        raise ModelFileError(path, "element vertex", "a vertex element", "none")
    before = elements[:names.index("vertex")]
    _, n, props = elements[names.index("vertex")]
    pnames = [p for p, _ in props]
    if any(c not in pnames for c in "xyz"):
        raise ModelFileError(path, "element vertex", "properties x, y and z", " ".join(pnames))
    if any(t == "list" for _, t in props):
        raise ModelFileError(path, "element vertex", "scalar properties", "a list property")
    if order[fmt_name] is None:
        skip = sum(e[1] for e in before)
        text = raw[start:].decode("ascii", "replace")
        body = text.splitlines()[skip:skip + n]
        table = _text_table(path, "\n".join(body), None, first_line=len(lines) + skip + 1)
        if len(table) != n:
            raise ModelFileError(path, "element vertex", f"{n} vertex lines", f"{len(table)}")
        if n and table.shape[1] != len(props):
            raise ModelFileError(path, "element vertex", f"{len(props)} values per line",
                                 f"{table.shape[1]}")
        if n == 0:
            return np.empty((0, 3)), comments
        return table[:, [pnames.index(c) for c in "xyz"]], comments
    endian = order[fmt_name]
    offset = start
    for name, count, eprops in before:
        if any(t == "list" for _, t in eprops):
            raise ModelFileError(path, f"element {name}", "the vertex element before any "
                                 "element with list properties", f"{name} first")
        offset += count * sum(np.dtype(t).itemsize for _, t in eprops)
    dtype = np.dtype([(p, endian + t) for p, t in props])
    need = n * dtype.itemsize
    if len(raw) - offset < need:
        raise ModelFileError(path, "element vertex", f"{n} vertices of {dtype.itemsize} bytes "
                             f"({need} bytes)", f"{max(len(raw) - offset, 0)} bytes")
    rec = np.frombuffer(raw, dtype=dtype, count=n, offset=offset)
    return np.column_stack([rec[c].astype(float) for c in "xyz"]), comments


# --- text and NumPy ---------------------------------------------------------------------------

def _text_table(path: str, text: str, delimiter: str | None, first_line: int = 1) -> NDArray:
    """A table of numbers from text; a bad value is a ModelFileError naming its line."""
    if not any(ln.split("#", 1)[0].strip() for ln in text.splitlines()):
        return np.empty((0, 0))
    try:
        return np.loadtxt(StringIO(text), delimiter=delimiter, comments="#", ndmin=2,
                          dtype=float)
    except ValueError as err:
        msg = str(err)
        m = re.search(r"could not convert string '(.*?)' to float64 at row (\d+)", msg)
        if m:
            # numpy counts rows among the non-empty, non-comment lines
            rows = [i for i, ln in enumerate(text.splitlines())
                    if ln.split("#", 1)[0].strip()]
            row = int(m.group(2))
            line = first_line + (rows[row] if row < len(rows) else row)
            raise ModelFileError(path, f"line {line}", "numbers", repr(m.group(1))) from None
        m = re.search(r"the number of columns changed from (\d+) to (\d+) at row (\d+)", msg)
        if m:
            rows = [i for i, ln in enumerate(text.splitlines())
                    if ln.split("#", 1)[0].strip()]
            row = int(m.group(3)) - 1
            line = first_line + (rows[row] if 0 <= row < len(rows) else row)
            raise ModelFileError(path, f"line {line}", f"{m.group(1)} values",
                                 f"{m.group(2)}") from None
        raise ModelFileError(path, "", "a table of numbers", msg.splitlines()[0]) from None


def _read_text(path: str, raw: bytes) -> tuple[NDArray, list[bytes]]:
    if b"\0" in raw[:4096]:
        raise ModelFileError(path, "", "a text file of x y z rows", "binary data")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ModelFileError(path, "", "a UTF-8 text file",
                             f"byte {raw[err.start]:#04x} at offset {err.start}") from None
    lines = text.splitlines()
    # The comments and header sit above the first data line: only those lines are looked at.
    comments, data = [], []
    for i, ln in enumerate(lines):
        if ln.lstrip().startswith("#"):
            comments.append(ln.encode())
        elif ln.split("#", 1)[0].strip():
            data.append((i, ln))
            if len(data) == 2:
                break
    if not data:
        return np.empty((0, 3)), comments
    first_i, first = data[0]
    delimiter = "," if "," in first else (";" if ";" in first else None)
    cells = [c.strip().lower() for c in (first.split(delimiter) if delimiter else first.split())]
    columns = [0, 1, 2]
    skip = 0
    if not all(is_number(c) for c in cells):                # a header row
        if any(c not in cells for c in "xyz"):
            raise ModelFileError(path, f"line {first_i + 1}", "a header naming columns x, y "
                                 "and z", first.strip()[:60])
        columns = [cells.index(c) for c in "xyz"]
        skip = first_i + 1
    body = "\n".join(lines[skip:])
    table = _text_table(path, body, delimiter, first_line=skip + 1)
    if table.size == 0:
        return np.empty((0, 3)), comments
    if table.shape[1] < 3:
        raise ModelFileError(path, f"line {data[1 if skip else 0][0] + 1}" if len(data) > 1
                             else "line 1", "at least 3 values per line (x y z)",
                             f"{table.shape[1]}")
    return table[:, columns], comments


def _read_npy(path: str, raw: bytes) -> tuple[NDArray, list[bytes]]:
    if not raw.startswith(b"\x93NUMPY"):
        raise ModelFileError(path, "", "a NumPy .npy file", repr(raw[:16]) if raw
                             else "an empty file")
    try:
        from io import BytesIO
        a = np.load(BytesIO(raw), allow_pickle=False)
    except (ValueError, OSError, EOFError) as err:
        raise ModelFileError(path, "", "a NumPy .npy array without Python objects",
                             str(err).splitlines()[0][:80]) from None
    if a.dtype.names:
        if any(c not in a.dtype.names for c in "xyz"):
            raise ModelFileError(path, "dtype", "fields x, y and z", ", ".join(a.dtype.names))
        return np.column_stack([a[c].astype(float).ravel() for c in "xyz"]), []
    if a.ndim != 2 or a.shape[1] < 3 or not np.issubdtype(a.dtype, np.number):
        raise ModelFileError(path, "array", "numbers of shape (N, 3) or (N, k > 3)",
                             f"{a.dtype} of shape {a.shape}")
    return a[:, :3].astype(float), []


_READERS = {".pcd": _read_pcd, ".ply": _read_ply, ".csv": _read_text, ".xyz": _read_text,
            ".txt": _read_text, ".npy": _read_npy}


def read_cloud(path: str | Path, units: Literal["m", "mm"] | None = None, *,
               nonfinite: Literal["drop", "refuse"] = "drop") -> Cloud:
    """Read a point cloud file into metres.

    Parameters
    ----------
    path : str or Path
        A .pcd, .ply, .csv, .xyz, .txt or .npy file.
    units : {"m", "mm"} or None
        The file's length unit; needed when the file does not declare one, and must agree
        with it when it does.
    nonfinite : {"drop", "refuse"}
        Drop points with NaN or inf and count them (`Cloud.dropped`), or refuse the file.

    Returns
    -------
    Cloud

    Raises
    ------
    ModelFileError
        Unreadable, not a cloud, malformed, empty, no unit, NaN/inf refused, implausible scale.
    InputError
        `units` or `nonfinite` not one of their values.
    """
    name = str(path)
    if nonfinite not in ("drop", "refuse"):
        raise InputError(f"nonfinite: expected 'drop' or 'refuse', found {nonfinite!r}")
    if units is not None and units not in UNITS:
        raise InputError(f"units: expected m or mm, found {units!r}")
    suffix = Path(name).suffix.lower()
    if suffix not in _READERS:
        raise ModelFileError(name, "", f"a cloud file ({', '.join(SUFFIXES)})",
                             f"the suffix {suffix!r}" if suffix else "no suffix")
    try:
        raw = Path(name).read_bytes()
    except OSError as err:
        raise ModelFileError(name, "", "a readable file", err.strerror or str(err)) from None
    points, comments = _READERS[suffix](name, raw)
    unit = _resolve_unit(name, _declared_unit(name, comments), units)
    total = len(points)
    if total == 0:
        raise ModelFileError(name, "points", "at least one point", "none")
    finite = np.isfinite(points).all(axis=1)
    dropped = int(total - finite.sum())
    if dropped and nonfinite == "refuse":
        first = int(np.flatnonzero(~finite)[0])
        raise ModelFileError(name, "points", "finite coordinates",
                             f"{dropped} point(s) with NaN or inf, the first at index {first}")
    points = points[finite] * UNITS[unit]
    if len(points) == 0:
        raise ModelFileError(name, "points", "at least one finite point",
                             f"none ({total} with NaN or inf)")
    check_scale(points, name)
    return Cloud(points=points, units=unit, dropped=dropped, path=name)


def write_pcd(path: str | Path, points: ArrayLike, units: Literal["m", "mm"] = "m", *,
              binary: bool = True) -> Path:
    """Write points (N, 3) given in m to a PCD file in `units`, declaring them in a comment.

    Parameters
    ----------
    path : str or Path
    points : array_like, shape (N, 3), m
    units : {"m", "mm"}
        The file's unit (the points are scaled to it).
    binary : bool
        DATA binary (float32, little-endian) or ascii.

    Returns
    -------
    Path
    """
    if units not in UNITS:
        raise InputError(f"units: expected m or mm, found {units!r}")
    p = np.asarray(points, float)
    if p.ndim != 2 or p.shape[1] != 3:
        raise InputError(f"points: expected shape (N, 3), found {p.shape}")
    p = p / UNITS[units]
    header = (f"# .PCD v0.7 - Point Cloud Data file format\n# units: {units}\nVERSION 0.7\n"
              f"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {len(p)}\nHEIGHT 1\n"
              f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {len(p)}\nDATA {'binary' if binary else 'ascii'}\n")
    path = Path(path)
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        if binary:
            f.write(p.astype("<f4").tobytes())
        else:
            np.savetxt(f, p, fmt="%.9g")
    return path
