"""Point-cloud files: PCD (ascii, binary, binary_compressed), PLY (ascii, binary), CSV/XYZ text
and NumPy .npy.

Every cloud has a length unit, m or mm: declared by the file (a comment such as ``# units: mm``
in PCD, CSV and XYZ files, ``comment units mm`` in PLY) or given by the caller; neither is an
error, and so is a caller's unit that contradicts the file's. The points come back in metres
(`armkit.perception.cloud.Cloud`: `points`, and the file's unit as `file_units`) and their
scale is checked (`check_scale`): a scene less than 5 cm across (a cloud in metres read as
millimetres) or with a median range beyond 1 km (millimetres read as metres) is refused.

PCD files are read as PCL writes them (its `PCDWriter`): ``DATA binary_compressed`` (the
default of PCL's tools: the fields one after another, LZF-compressed, decoded here), binary
and ascii, organised clouds (``WIDTH`` x ``HEIGHT``, with NaN where a ray had no return), and
any extra fields (intensity, ring, timestamp, normals, rgb), which are kept by name in
`Cloud.fields` (one value per point) or ignored (``fields=``). Older PCL versions pad the file
with zero bytes to a 4,096-byte page: that padding is accepted, any other byte past the data is
not.

Every read is bounded: regular files only (not a device, pipe or directory, however linked),
at most `MAX_BYTES` bytes, and a header's counts are checked against the body exactly before
anything is allocated from them. Points with NaN or inf (LiDARs write them for rays with no
return) are dropped and counted, or the file is refused, as the caller chooses. Every failure
is one `ModelFileError` naming the file, the field, what was expected and what was found.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass
from io import BytesIO
from pathlib import Path
from typing import Literal, Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError, ModelFileError
from armkit.io.documents import LARGEST, found_text, number_from_text, read_bytes
from armkit.jit import kernel
from armkit.perception.cloud import Cloud, check_scale

UNITS = {"m": 1.0, "mm": 1e-3}
SUFFIXES = (".pcd", ".ply", ".csv", ".xyz", ".txt", ".npy")
MAX_BYTES = 512 * 2**20
"""The largest cloud file read by default (bytes); `read_cloud`'s ``max_bytes`` raises it."""
MAX_POINTS = 200_000_000    # points of one cloud: 2.4 GB of float32 x, y, z
MAX_COUNT = 4096            # values of one PCD field per point (a descriptor has 33 to 512)
MAX_HEADER_LINES = 200
MAX_WALKED = 1_000_000     # items of a PLY list element (mixed polygons) walked one by one
PAGE = 4096                 # bytes: older PCL versions pad files to a page with zeros
# LZF turns at most 264 bytes into 3 (a back-reference of the longest length): no stream can
# grow by more than 88 times. A header that claims more is not an LZF stream's.
LZF_MAX_RATIO = 88
_UNIT_COMMENT = re.compile(rb"\bunits?\s*[:=]?\s*(mm|m)\b", re.IGNORECASE)
# Bytes of a text table of numbers: digits, signs, dots, exponents, nan and inf, separators.
# (NumPy's float parser also takes 1_000 as 1000: an underscore is not let through.)
_TEXT_NUMBER_BYTES = np.zeros(256, bool)
_TEXT_NUMBER_BYTES[list(b"0123456789+-.eE \t\r\nnaNAifIFtyTY")] = True


def _declared_unit(path: str, comments: list[bytes]) -> str | None:
    """The unit a file's comments declare, if any."""
    found = {m.group(1).decode().lower() for c in comments for m in _UNIT_COMMENT.finditer(c)}
    if len(found) > 1:
        raise ModelFileError(path, "units", "one declared unit", " and ".join(sorted(found)))
    return found.pop() if found else None


def _resolve_unit(path: str, declared: str | None, given: str | None) -> str:
    if declared is not None and given is not None and declared != given:
        raise ModelFileError(path, "units", f"{given} as given by the caller",
                             f"the file declares {declared}")
    unit = declared or given
    if unit is None:
        raise ModelFileError(path, "units", "a length unit, m or mm, declared in the file or "
                             "given (units= or --units)", "none")
    return unit


@dataclass
class _Table:
    """What a reader found: coordinates (k, 3) in file units, extra fields, comments, grid."""

    xyz: NDArray
    extra: dict[str, NDArray]
    comments: list[bytes]
    width: int = 0
    height: int = 1


# --- LZF (PCL's binary_compressed) -----------------------------------------------------------
# The format of liblzf (Marc Lehmann), which PCL uses: a stream of runs, each opened by a
# control byte c. c < 32: c + 1 literal bytes follow. Else a back-reference: length c >> 5
# (7: plus the next byte), plus 2; distance ((c & 31) << 8) + the next byte, plus 1, back from
# the end of the output so far; copied byte by byte, so that it may overlap what it writes.

@kernel(cache=True, nogil=True)
def _lzf_decode(source, target):
    """Decode LZF `source` (uint8) into `target` (uint8): the bytes written, -1 for a corrupt
    stream, -2 if it decodes to more than `target` holds."""
    n, m = len(source), len(target)
    i = 0
    out = 0
    while i < n:
        control = int(source[i])
        i += 1
        if control < 32:
            run = control + 1
            if i + run > n:
                return -1
            if out + run > m:
                return -2
            target[out:out + run] = source[i:i + run]
            i += run
            out += run
        else:
            length = control >> 5
            if length == 7:
                if i >= n:
                    return -1
                length += int(source[i])
                i += 1
            if i >= n:
                return -1
            back = out - ((control & 31) << 8) - 1 - int(source[i])
            i += 1
            length += 2
            if back < 0:
                return -1
            if out + length > m:
                return -2
            if back + length <= out:
                target[out:out + length] = target[back:back + length]
            else:
                for k in range(length):
                    target[out + k] = target[back + k]
            out += length
    return out


@kernel(cache=True, nogil=True)
def _lzf_encode(source, target, table):
    """LZF-compress `source` (uint8) into `target` (uint8, at least len + len // 32 + 16),
    `table` an int64 hash table of 2**14 entries set to -1: the bytes written."""
    n = len(source)
    i = 0
    out = 1                         # target[0] holds the first literal run's control byte
    literal = 0
    while i < n:
        match = 0
        if i + 2 < n:
            h = ((int(source[i]) << 16) | (int(source[i + 1]) << 8) | int(source[i + 2]))
            h = ((h * 2654435761) >> 10) & 16383
            ref = table[h]
            table[h] = i
            if ref >= 0 and i - ref - 1 < 8192 and source[ref] == source[i] \
                    and source[ref + 1] == source[i + 1] and source[ref + 2] == source[i + 2]:
                longest = min(n - i, 264)
                match = 3
                while match < longest and source[ref + match] == source[i + match]:
                    match += 1
                distance = i - ref - 1
        if match:
            if literal:
                target[out - literal - 1] = literal - 1
            else:
                out -= 1            # no literals: the placeholder control byte goes
            code = match - 2
            if code < 7:
                target[out] = (distance >> 8) + (code << 5)
                out += 1
            else:
                target[out] = (distance >> 8) + (7 << 5)
                target[out + 1] = code - 7
                out += 2
            target[out] = distance & 255
            out += 2                # and a placeholder for the next literal run
            literal = 0
            i += match
        else:
            target[out] = source[i]
            out += 1
            literal += 1
            i += 1
            if literal == 32:
                target[out - 33] = 31
                literal = 0
                out += 1
    if literal:
        target[out - literal - 1] = literal - 1
    else:
        out -= 1
    return out


def lzf_decompress(data: bytes, size: int) -> bytes:
    """Decode an LZF stream (liblzf's format, as in PCL's binary_compressed PCD files).

    Parameters
    ----------
    data : bytes
    size : int
        The decoded length the stream must have, bytes.

    Returns
    -------
    bytes

    Raises
    ------
    ValueError
        A corrupt stream, or one that does not decode to exactly `size` bytes.
    """
    source = np.frombuffer(data, np.uint8)
    target = np.empty(size, np.uint8)
    written = _lzf_decode.sized(len(source), source, target, few=8192)
    if written == -1:
        raise ValueError("a corrupt LZF stream")
    if written == -2 or written != size:
        raise ValueError(f"an LZF stream of {size} bytes decoded, found "
                         + ("more" if written == -2 else f"{written}"))
    return target.tobytes()


def lzf_compress(data: bytes) -> bytes:
    """LZF-compress `data` (liblzf's format: what `lzf_decompress` and PCL read)."""
    source = np.frombuffer(data, np.uint8)
    target = np.zeros(len(source) + len(source) // 32 + 16, np.uint8)
    table = np.full(2**14, -1, np.int64)
    return target[:_lzf_encode.sized(len(source), source, target, table, few=8192)].tobytes()


# --- PCD ------------------------------------------------------------------------------------

_PCD_TYPES = {("F", 4): "f4", ("F", 8): "f8", ("I", 1): "i1", ("I", 2): "i2", ("I", 4): "i4",
              ("I", 8): "i8", ("U", 1): "u1", ("U", 2): "u2", ("U", 4): "u4", ("U", 8): "u8"}
_PCD_KEYS = ("VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT",
             "POINTS", "DATA")


def _header_lines(path: str, raw: bytes, what: str, first: tuple[bytes, ...], end) -> tuple:
    """Split an ASCII header off `raw`: (lines, offset of the data). `end(line)` ends it."""
    if not raw[:4096].lstrip().startswith(first):
        names = [f.decode() for f in first]
        starts = names[0] if len(names) == 1 else ", ".join(names[:-1]) + " or " + names[-1]
        raise ModelFileError(path, "", f"a {what} file (starting with {starts})",
                             "an empty file" if not raw else found_text(raw[:16]))
    lines, pos = [], 0
    while pos < len(raw) and len(lines) < MAX_HEADER_LINES:
        nl = raw.find(b"\n", pos, pos + 65_536)
        if nl < 0:
            nl = min(len(raw), pos + 65_536)
        line = raw[pos:nl].rstrip(b"\r")
        pos = nl + 1
        lines.append(line)
        if end(line):
            return lines, pos
    raise ModelFileError(path, "header", f"a {what} header of at most {MAX_HEADER_LINES} lines "
                         "ending in its data line", "no end of header")


def _whole(path: str, field: str, text: str, low: int, high: int) -> int:
    return number_from_text(text, path, field, low, high, integer=True)


def _pcd_header(path: str, lines: list[bytes]) -> dict[str, list[str]]:
    header: dict[str, list[str]] = {}
    for number, ln in enumerate(lines, start=1):
        try:
            parts = ln.decode("ascii").split()
        except UnicodeDecodeError:
            raise ModelFileError(path, f"header line {number}", "ASCII text",
                                 found_text(ln[:40])) from None
        if not parts or parts[0].startswith("#"):
            continue
        key = parts[0].upper()
        if key not in _PCD_KEYS:
            raise ModelFileError(path, f"header line {number}", "one of " + ", ".join(_PCD_KEYS),
                                 found_text(parts[0]))
        if key in header:
            raise ModelFileError(path, key, "one line", "two")
        header[key] = parts[1:]
    return header


def _read_pcd(path: str, raw: bytes, max_bytes: int) -> _Table:
    lines, start = _header_lines(path, raw, "PCD", (b"#", b"VERSION", b"FIELDS"),
                                 lambda line: line.strip().upper().startswith(b"DATA"))
    comments = [ln for ln in lines if ln.strip().startswith(b"#")]
    header = _pcd_header(path, lines)
    fields = header.get("FIELDS")
    if not fields:
        raise ModelFileError(path, "FIELDS", "a FIELDS line naming x y z", "none")
    k = len(fields)
    named = [f for f in fields if f != "_"]          # "_": PCL's padding, no field of its own
    twice = next((f for f in named if named.count(f) > 1), None)
    if twice is not None:
        raise ModelFileError(path, "FIELDS", "each field named once", f"{twice!r} twice")
    if any(c not in fields for c in "xyz"):
        raise ModelFileError(path, "FIELDS", "fields x, y and z", found_text(" ".join(fields)))
    sizes = header.get("SIZE", ["4"] * k)
    types = header.get("TYPE", ["F"] * k)
    counts = header.get("COUNT", ["1"] * k)
    for name, values in (("SIZE", sizes), ("TYPE", types), ("COUNT", counts)):
        if len(values) != k:
            raise ModelFileError(path, name, f"{k} entries, one per field", f"{len(values)}")
    sizes_i = [_whole(path, f"SIZE of {f}", s, 1, 8) for f, s in zip(fields, sizes)]
    counts_i = [_whole(path, f"COUNT of {f}", c, 1, MAX_COUNT) for f, c in zip(fields, counts)]
    dtypes = []
    for name, t, s in zip(fields, types, sizes_i):
        if (t.upper(), s) not in _PCD_TYPES:
            raise ModelFileError(path, f"TYPE/SIZE of {name}", "F 4/8, I or U 1/2/4/8",
                                 found_text(f"{t} {s}"))
        dtypes.append(_PCD_TYPES[t.upper(), s])
    for c in "xyz":
        i = fields.index(c)
        if counts_i[i] != 1 or dtypes[i][0] != "f":
            raise ModelFileError(path, f"field {c}", "one float (TYPE F, COUNT 1)",
                                 f"{counts_i[i]} of TYPE {types[i]}")
    if "WIDTH" not in header:
        raise ModelFileError(path, "WIDTH", "the number of points in a row", "none")
    width = _whole(path, "WIDTH", " ".join(header["WIDTH"]), 0, MAX_POINTS)
    height = _whole(path, "HEIGHT", " ".join(header.get("HEIGHT", ["1"])), 0, MAX_POINTS)
    n = width * height
    if "POINTS" in header:
        points = _whole(path, "POINTS", " ".join(header["POINTS"]), 0, MAX_POINTS)
        if points != n:
            raise ModelFileError(path, "POINTS", f"WIDTH x HEIGHT = {width} x {height} = {n}",
                                 f"{points}")
    if n > MAX_POINTS:
        raise ModelFileError(path, "WIDTH/HEIGHT", f"at most {MAX_POINTS:,} points", f"{n:,}")
    data = " ".join(header.get("DATA", [])).lower()
    point_bytes = sum(s * c for s, c in zip(sizes_i, counts_i))
    names = [f if f != "_" else f"_{i}" for i, f in enumerate(fields)]
    dtype = np.dtype([(nm, "<" + dt, (c,)) if c > 1 else (nm, "<" + dt)
                      for nm, dt, c in zip(names, dtypes, counts_i)])
    body = memoryview(raw)[start:]
    if data == "ascii":
        table = _ascii_rows(path, bytes(body), n, sum(counts_i), len(lines))
        columns = np.cumsum([0] + counts_i)
        values = {nm: table[:, columns[i]] for i, nm in enumerate(names) if counts_i[i] == 1}
    elif data == "binary":
        _check_body(path, "DATA binary", body, n * point_bytes,
                    f"{n} points of {point_bytes} bytes")
        rec = np.frombuffer(body, dtype=dtype, count=n)
        values = {nm: rec[nm] for nm, c in zip(names, counts_i) if c == 1}
    elif data == "binary_compressed":
        values = _compressed(path, body, n, names, dtypes, sizes_i, counts_i, max_bytes)
    else:
        raise ModelFileError(path, "DATA", "ascii, binary or binary_compressed",
                             found_text(data) if data else "nothing")
    xyz = np.column_stack([values[c].astype(float) for c in "xyz"])
    extra = {nm: values[nm] for nm in names
             if nm not in "xyz" and not nm.startswith("_") and nm in values}
    return _Table(xyz, extra, comments, width, height)


def _check_body(path: str, where: str, body, size: int, what: str) -> None:
    """The body holds exactly `size` bytes, or PCL's zero padding to a page after them."""
    extra = len(body) - size
    if extra < 0:
        raise ModelFileError(path, where, f"{what} ({size:,} bytes)", f"{len(body):,} bytes")
    if extra and (extra >= PAGE or np.frombuffer(body, np.uint8, offset=size).any()):
        raise ModelFileError(path, where, f"{what} ({size:,} bytes) and nothing after them "
                             "(or PCL's zero padding to a page)", f"{extra:,} bytes more")


def _compressed(path, body, n, names, dtypes, sizes, counts, max_bytes) -> dict:
    """The fields of a binary_compressed body: two uint32 sizes, then an LZF stream of the
    fields one after another (each field's values for every point together)."""
    where = "DATA binary_compressed"
    if len(body) < 8:
        raise ModelFileError(path, where, "the compressed and uncompressed sizes (8 bytes)",
                             f"{len(body)} bytes")
    packed, unpacked = struct.unpack_from("<II", body)
    need = n * sum(s * c for s, c in zip(sizes, counts))
    if unpacked != need:
        raise ModelFileError(path, where, f"an uncompressed size of {need:,} bytes ({n} points "
                             "as FIELDS, SIZE and COUNT give)", f"{unpacked:,}")
    if unpacked > max(LZF_MAX_RATIO * packed, 0) + 64 or unpacked > 4 * max_bytes:
        raise ModelFileError(path, where, f"an uncompressed size that {packed:,} compressed "
                             f"bytes can hold (at most {LZF_MAX_RATIO} times as many, and at most "
                             f"{4 * max_bytes:,})", f"{unpacked:,}")
    _check_body(path, where, body[8:], packed, "the compressed size's bytes")
    if unpacked == 0:
        decoded = b""
    else:
        try:
            decoded = lzf_decompress(bytes(body[8:8 + packed]), unpacked)
        except ValueError as err:
            raise ModelFileError(path, where, "an LZF stream (as PCL writes it)",
                                 str(err).removeprefix("an LZF stream of ")) from None
    values, offset = {}, 0
    for nm, dt, s, c in zip(names, dtypes, sizes, counts):
        if c == 1:
            values[nm] = np.frombuffer(decoded, "<" + dt, count=n, offset=offset)
        offset += n * s * c
    return values


def _ascii_rows(path: str, body: bytes, n: int, k: int, header_lines: int) -> NDArray:
    """`n` lines of `k` numbers each (nan and inf allowed: no return), checked exactly."""
    arr = np.frombuffer(body, np.uint8)
    bad = np.flatnonzero(~_TEXT_NUMBER_BYTES[arr])
    if bad.size:
        at = int(bad[0])
        line = header_lines + 1 + body.count(b"\n", 0, at)
        start, end = body.rfind(b"\n", 0, at) + 1, body.find(b"\n", at)
        text = body[max(start, at - 30):end if 0 <= end < at + 30 else at + 30]
        raise ModelFileError(path, f"line {line}", "numbers",
                             found_text(text.decode("latin-1").strip()))
    # Tokens per line, without a Python loop: a token starts where a non-space follows a space.
    space = (arr == 32) | (arr == 9) | (arr == 13) | (arr == 10)
    starts = np.flatnonzero(~space & np.concatenate([[True], space[:-1]]))
    line_of = np.cumsum(arr == 10)[starts] if starts.size else starts
    lines, per_line = np.unique(line_of, return_counts=True)
    if len(lines) != n:
        raise ModelFileError(path, "POINTS", f"{n} data lines", f"{len(lines)}")
    wrong = np.flatnonzero(per_line != k)
    if wrong.size:
        line = header_lines + 1 + int(lines[wrong[0]])
        raise ModelFileError(path, f"line {line}", f"{k} values (FIELDS, COUNT)",
                             f"{int(per_line[wrong[0]])}")
    if n == 0:
        return np.empty((0, k))
    tokens = body.split()
    try:
        table = np.array(tokens, dtype=object).astype(np.float64)
    except ValueError as err:
        raise ModelFileError(path, "DATA ascii", "numbers",
                             found_text(str(err).rpartition(" ")[2])) from None
    # inf is a word (no return); a number too large for a double is not, however it reads.
    for i in np.flatnonzero(np.isinf(table))[:1000]:
        if tokens[i].lstrip(b"+-").lower() not in (b"inf", b"infinity"):
            line = header_lines + 1 + int(line_of[i]) if line_of.size else header_lines + 1
            raise ModelFileError(path, f"line {line}", "numbers within a double's range",
                                 found_text(tokens[i].decode("latin-1")))
    return table.reshape(n, k)


# --- PLY ------------------------------------------------------------------------------------

_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
              "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
              "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
              "float64": "f8"}


def _read_ply(path: str, raw: bytes, max_bytes: int) -> _Table:
    lines, start = _header_lines(path, raw, "PLY", (b"ply",),
                                 lambda line: line.strip() == b"end_header")
    if lines[0].strip() != b"ply":
        raise ModelFileError(path, "line 1", "ply", found_text(lines[0][:20]))
    comments = [ln for ln in lines if ln.startswith((b"comment", b"obj_info"))]
    fmt = next((ln.split() for ln in lines if ln.startswith(b"format")), None)
    if not fmt or len(fmt) < 2:
        raise ModelFileError(path, "format", "a format line", "none")
    fmt_name = fmt[1].decode("ascii", "replace")
    order = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}
    if fmt_name not in order:
        raise ModelFileError(path, "format", "ascii, binary_little_endian or "
                             "binary_big_endian", found_text(fmt_name))
    # [name, count, [(property, dtype or ("list", count dtype, item dtype))]]
    elements: list[list] = []
    for ln in lines[1:]:
        parts = ln.decode("ascii", "replace").split()
        if parts[:1] == ["element"]:
            if len(parts) != 3:
                raise ModelFileError(path, "element", "element NAME COUNT",
                                     found_text(" ".join(parts)))
            if parts[1] in (e[0] for e in elements):
                raise ModelFileError(path, f"element {parts[1][:40]}", "each element once",
                                     "twice")
            count = _whole(path, f"element {parts[1][:40]}", parts[2], 0, MAX_POINTS)
            elements.append([parts[1], count, []])
        elif parts[:1] == ["property"]:
            if not elements:
                raise ModelFileError(path, "property", "an element before its properties",
                                     found_text(" ".join(parts)))
            where = f"element {elements[-1][0][:40]}: property"
            if len(parts) == 5 and parts[1] == "list" and parts[2] in _PLY_TYPES \
                    and parts[3] in _PLY_TYPES and _PLY_TYPES[parts[2]][0] in "iu":
                prop = (parts[4], ("list", _PLY_TYPES[parts[2]], _PLY_TYPES[parts[3]]))
            elif len(parts) == 3 and parts[1] in _PLY_TYPES:
                prop = (parts[2], _PLY_TYPES[parts[1]])
            else:
                raise ModelFileError(path, where, "a type such as float, double, int, uchar "
                                     "(or list COUNT-TYPE TYPE)", found_text(" ".join(parts)))
            if prop[0] in (p for p, _ in elements[-1][2]):
                raise ModelFileError(path, where, "each property named once",
                                     f"{prop[0][:40]!r} twice")
            elements[-1][2].append(prop)
    names = [e[0] for e in elements]
    if "vertex" not in names:
        raise ModelFileError(path, "element vertex", "a vertex element", "none")
    at = names.index("vertex")
    _, n, props = elements[at]
    pnames = [p for p, _ in props]
    if any(c not in pnames for c in "xyz"):
        raise ModelFileError(path, "element vertex", "properties x, y and z",
                             found_text(" ".join(pnames)))
    if any(isinstance(t, tuple) for _, t in props):
        raise ModelFileError(path, "element vertex", "scalar properties", "a list property")
    if order[fmt_name] is None:
        values = _ply_ascii(path, raw[start:], elements, at, len(lines))
    else:
        values = _ply_binary(path, memoryview(raw)[start:], elements, at, order[fmt_name])
    xyz = np.column_stack([values[c].astype(float) for c in "xyz"])
    return _Table(xyz, {p: values[p] for p in pnames if p not in "xyz"}, comments)


def _ply_ascii(path: str, body: bytes, elements: list, at: int, header_lines: int) -> dict:
    """The vertex values of an ascii PLY body: one line per element item, exactly."""
    text = body.split(b"\n")
    if text and not text[-1].strip():
        text = text[:-1]
    total = sum(e[1] for e in elements)
    if len(text) != total:
        raise ModelFileError(path, "element counts", f"{total} data lines (the sum of the "
                             "element counts)", f"{len(text)}")
    skip = sum(e[1] for e in elements[:at])
    _, n, props = elements[at]
    table = _ascii_rows(path, b"\n".join(text[skip:skip + n]) + b"\n", n, len(props),
                        header_lines + skip)
    return {p: table[:, i] for i, (p, _) in enumerate(props)}


def _ply_binary(path: str, body, elements: list, at: int, endian: str) -> dict:
    """The vertex values of a binary PLY body; every element's size checked against the body
    (a list element's items by their counts)."""
    offset, values = 0, {}
    for index, (name, count, props) in enumerate(elements):
        where = f"element {name[:40]}"
        if any(isinstance(t, tuple) for _, t in props):
            offset = _ply_lists(path, body, offset, count, props, endian, where)
            continue
        dtype = np.dtype([(p, endian + t) for p, t in props]) if props else np.dtype("V0")
        need = count * dtype.itemsize
        if len(body) - offset < need:
            raise ModelFileError(path, where, f"{count} items of {dtype.itemsize} bytes "
                                 f"({need:,} bytes)", f"{max(len(body) - offset, 0):,} bytes")
        if index == at:
            rec = np.frombuffer(body, dtype=dtype, count=count, offset=offset)
            values = {p: rec[p] for p, _ in props}
        offset += need
    if len(body) != offset:
        raise ModelFileError(path, "element counts", f"a body of {offset:,} bytes (the elements "
                             "as the header gives them)", f"{len(body):,} bytes")
    return values


def _ply_lists(path, body, offset, count, props, endian, where) -> int:
    """The offset after `count` items of an element with list properties (faces). Items of one
    length (triangles) are checked at once; others are walked item by item."""
    def size(t):
        return np.dtype(t).itemsize

    scalar = sum(size(t) for _, t in props if not isinstance(t, tuple))
    lists = [t for _, t in props if isinstance(t, tuple)]
    if count == 0:
        return offset
    if len(props) == 1 and len(lists) == 1:
        _, count_type, item_type = lists[0]
        head = np.frombuffer(body, endian + count_type, count=1, offset=offset) \
            if len(body) - offset >= size(count_type) else None
        if head is not None and head[0] >= 0:
            stride = size(count_type) + int(head[0]) * size(item_type)
            if len(body) - offset >= count * stride:
                heads = np.ndarray((count,), endian + count_type, body, offset, (stride,))
                if (heads == head[0]).all():
                    return offset + count * stride
    if count > MAX_WALKED:
        raise ModelFileError(path, where, f"items of one list length, or at most "
                             f"{MAX_WALKED:,} items of mixed lengths", f"{count:,} items")
    for item in range(count):
        offset += scalar
        for _, count_type, item_type in lists:
            if len(body) - offset < size(count_type):
                raise ModelFileError(path, f"{where}[{item}]", "a list count", "the end of "
                                     "the file")
            k = int(np.frombuffer(body, endian + count_type, count=1, offset=offset)[0])
            if k < 0:
                raise ModelFileError(path, f"{where}[{item}]", "a list count of 0 or more",
                                     str(k))
            offset += size(count_type) + k * size(item_type)
        if offset > len(body):
            raise ModelFileError(path, f"{where}[{item}]", "its list items", "the end of the "
                                 "file")
    return offset


# --- text and NumPy ---------------------------------------------------------------------------

def _read_text(path: str, raw: bytes, max_bytes: int) -> _Table:
    if b"\0" in raw[:4096]:
        raise ModelFileError(path, "", "a text file of x y z rows", "binary data")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ModelFileError(path, "", "a UTF-8 text file",
                             f"byte {raw[err.start]:#04x} at offset {err.start}") from None
    lines = text.splitlines()
    comments, first_i = [], None
    for i, ln in enumerate(lines):
        if ln.lstrip().startswith("#"):
            comments.append(ln.encode())
        elif ln.strip():
            first_i = i
            break
    if first_i is None:
        return _Table(np.empty((0, 3)), {}, comments)
    first = lines[first_i]
    delimiter = "," if "," in first else (";" if ";" in first else None)
    cells = [c.strip() for c in (first.split(delimiter) if delimiter else first.split())]
    if all(_is_cell_number(c) for c in cells):
        names, skip = [f"column {i + 1}" for i in range(len(cells))], first_i
        if len(cells) < 3:
            raise ModelFileError(path, f"line {first_i + 1}", "at least 3 values per line "
                                 "(x y z)", f"{len(cells)}")
        columns = {"x": 0, "y": 1, "z": 2}
    else:                                                   # a header row
        names = [c.lower() for c in cells]
        if any(c not in names for c in "xyz"):
            raise ModelFileError(path, f"line {first_i + 1}", "a header naming columns x, y "
                                 "and z", found_text(first.strip()))
        twice = next((c for c in names if names.count(c) > 1), None)
        if twice is not None:
            raise ModelFileError(path, f"line {first_i + 1}", "each column named once",
                                 f"{twice[:40]!r} twice")
        columns = {c: names.index(c) for c in "xyz"}
        skip = first_i + 1
    body = "\n".join(ln.split("#", 1)[0].replace(delimiter or " ", " ")
                     for ln in lines[skip:])
    rows = [ln for ln in body.split("\n") if ln.strip()]
    table = _ascii_rows(path, "\n".join(rows).encode() + b"\n", len(rows), len(names),
                        skip) if rows else np.empty((0, len(names)))
    extra = {nm: table[:, i] for i, nm in enumerate(names)
             if i not in columns.values() and not nm.startswith("column ")}
    return _Table(table[:, [columns[c] for c in "xyz"]], extra, comments)


def _is_cell_number(text: str) -> bool:
    try:
        number_from_text(text, "", "", -np.inf, np.inf)
    except ModelFileError:
        return text.lower().lstrip("+-") in ("nan", "inf", "infinity")
    return True


def _read_npy(path: str, raw: bytes, max_bytes: int) -> _Table:
    if not raw.startswith(b"\x93NUMPY"):
        raise ModelFileError(path, "", "a NumPy .npy file", found_text(raw[:16]) if raw
                             else "an empty file")
    try:
        a = np.load(BytesIO(raw), allow_pickle=False)
    except (ValueError, OSError, EOFError, TypeError) as err:
        raise ModelFileError(path, "", "a NumPy .npy array without Python objects",
                             found_text(str(err).splitlines()[0] if str(err) else "")) from None
    if a.dtype.names:
        if any(c not in a.dtype.names for c in "xyz"):
            raise ModelFileError(path, "dtype", "fields x, y and z",
                                 found_text(", ".join(a.dtype.names)))
        if any(not np.issubdtype(a.dtype[c], np.number) or a.dtype[c].shape for c in "xyz"):
            raise ModelFileError(path, "dtype", "numeric fields x, y and z", str(a.dtype)[:80])
        extra = {nm: a[nm].ravel() for nm in a.dtype.names if nm not in "xyz"
                 and np.issubdtype(a.dtype[nm], np.number) and not a.dtype[nm].shape}
        return _Table(np.column_stack([a[c].astype(float).ravel() for c in "xyz"]), extra, [])
    if a.ndim != 2 or a.shape[1] < 3 or not np.issubdtype(a.dtype, np.number) \
            or np.issubdtype(a.dtype, np.complexfloating):
        raise ModelFileError(path, "array", "real numbers of shape (N, 3) or (N, k > 3)",
                             f"{a.dtype} of shape {a.shape}")
    return _Table(a[:, :3].astype(float), {}, [])


_READERS = {".pcd": _read_pcd, ".ply": _read_ply, ".csv": _read_text, ".xyz": _read_text,
            ".txt": _read_text, ".npy": _read_npy}


def read_cloud(path: str | Path, units: Literal["m", "mm"] | None = None, *,
               nonfinite: Literal["drop", "refuse"] = "drop",
               fields: Sequence[str] | None = None, max_bytes: int = MAX_BYTES) -> Cloud:
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
    fields : sequence of str, optional
        The extra per-point fields to keep (each must be in the file); None keeps every one
        with one number per point, ``()`` none.
    max_bytes : int
        The largest file read, bytes.

    Returns
    -------
    Cloud

    Raises
    ------
    ModelFileError
        Unreadable, not a regular file, larger than `max_bytes`, not a cloud, counts that
        disagree with the body, empty, no unit, NaN/inf refused, coordinates beyond 1e9 of the
        file's unit, implausible scale.
    InputError
        `units`, `nonfinite` or `fields` not one of their values.
    """
    name = str(path)
    if nonfinite not in ("drop", "refuse"):
        raise InputError(f"nonfinite: expected 'drop' or 'refuse', found {found_text(nonfinite)}")
    if units is not None and units not in UNITS:
        raise InputError(f"units: expected m or mm, found {found_text(units)}")
    if fields is not None and (isinstance(fields, str)
                               or not all(isinstance(f, str) for f in fields)):
        raise InputError(f"fields: expected a sequence of field names, found "
                         f"{found_text(fields)}")
    suffix = Path(name).suffix.lower()
    if suffix not in _READERS:
        raise ModelFileError(name, "", f"a cloud file ({', '.join(SUFFIXES)})",
                             f"the suffix {found_text(suffix)}" if suffix else "no suffix")
    raw = read_bytes(name, max_bytes)
    table = _READERS[suffix](name, raw, max_bytes)
    unit = _resolve_unit(name, _declared_unit(name, table.comments), units)
    xyz = table.xyz
    total = len(xyz)
    if total == 0:
        raise ModelFileError(name, "points", "at least one point", "none")
    finite = np.isfinite(xyz).all(axis=1)
    dropped = int(total - finite.sum())
    if dropped and nonfinite == "refuse":
        first = int(np.flatnonzero(~finite)[0])
        raise ModelFileError(name, "points", "finite coordinates",
                             f"{dropped} point(s) with NaN or inf, the first at index {first}")
    far = np.flatnonzero(finite & (np.abs(xyz) > LARGEST).any(axis=1))
    if far.size:
        raise ModelFileError(name, f"point {int(far[0])}", f"coordinates within {LARGEST:g} "
                             f"{unit}", found_text(xyz[far[0]].tolist()))
    keep = np.flatnonzero(finite)
    if not len(keep):
        raise ModelFileError(name, "points", "at least one finite point",
                             f"none ({total} with NaN or inf)")
    if fields is None:
        kept = table.extra
    else:
        missing = [f for f in fields if f not in table.extra]
        if missing:
            raise ModelFileError(name, "fields", f"the field {found_text(missing[0])} asked for",
                                 "fields " + found_text(", ".join(table.extra) or "none"))
        kept = {f: table.extra[f] for f in fields}
    points = xyz[keep] * UNITS[unit]
    check_scale(points, name)
    return Cloud(points=points, file_units=unit, dropped=dropped, path=name,
                 fields={f: np.ascontiguousarray(v[keep]) for f, v in kept.items()},
                 index=keep, width=table.width or total, height=table.height)


def write_pcd(path: str | Path, points: ArrayLike, units: Literal["m", "mm"] = "m", *,
              data: Literal["binary_compressed", "binary", "ascii"] = "binary_compressed",
              fields: Mapping[str, ArrayLike] | None = None,
              width: int | None = None) -> Path:
    """Write points (N, 3) given in m to a PCD file as PCL writes it, in `units`, declared in a
    comment.

    Parameters
    ----------
    path : str or Path
    points : array_like, shape (N, 3), m
        NaN allowed (an organised cloud's rays without a return).
    units : {"m", "mm"}
        The file's unit (the points are scaled to it).
    data : {"binary_compressed", "binary", "ascii"}
        PCL's three layouts: binary_compressed (its default: LZF of the fields one after
        another), binary (float32 per point, little-endian) or ascii.
    fields : mapping of str to array_like (N,), optional
        Extra per-point fields (float32; a field named ``ring`` as uint16).
    width : int, optional
        An organised cloud's row length (N must be a multiple); default N (one row).

    Returns
    -------
    Path
    """
    if units not in UNITS:
        raise InputError(f"units: expected m or mm, found {found_text(units)}")
    if data not in ("binary_compressed", "binary", "ascii"):
        raise InputError(f"data: expected binary_compressed, binary or ascii, found "
                         f"{found_text(data)}")
    p = np.asarray(points, float)
    if p.ndim != 2 or p.shape[1] != 3:
        raise InputError(f"points: expected shape (N, 3), found {p.shape}")
    n = len(p)
    width = n if width is None else int(width)
    if width < 1 and n or (n and n % width):
        raise InputError(f"width: expected a divisor of the {n} points, found {width}")
    columns = {"x": p[:, 0] / UNITS[units], "y": p[:, 1] / UNITS[units],
               "z": p[:, 2] / UNITS[units]}
    for name, values in (fields or {}).items():
        v = np.asarray(values)
        if v.shape != (n,):
            raise InputError(f"fields[{name!r}]: expected shape ({n},), found {v.shape}")
        columns[name] = v
    typed = {name: (np.asarray(v, "<u2") if name == "ring" else np.asarray(v, "<f4"))
             for name, v in columns.items()}
    header = ("# .PCD v0.7 - Point Cloud Data file format\n"
              f"# units: {units}\nVERSION 0.7\nFIELDS {' '.join(typed)}\n"
              f"SIZE {' '.join(str(v.itemsize) for v in typed.values())}\n"
              f"TYPE {' '.join('U' if v.dtype.kind == 'u' else 'F' for v in typed.values())}\n"
              f"COUNT {' '.join('1' for _ in typed)}\n"
              f"WIDTH {width if n else 0}\nHEIGHT {n // width if n else 1}\n"
              f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {data}\n")
    path = Path(path)
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        if data == "ascii":
            table = np.column_stack([v.astype(float) for v in typed.values()]) if n else \
                np.empty((0, len(typed)))
            np.savetxt(f, table, fmt="%.9g")
        elif data == "binary":
            record = np.empty(n, [(name, v.dtype) for name, v in typed.items()])
            for name, v in typed.items():
                record[name] = v
            f.write(record.tobytes())
        else:
            raw = b"".join(v.tobytes() for v in typed.values())
            packed = lzf_compress(raw) if raw else b""
            f.write(struct.pack("<II", len(packed), len(raw)) + packed)
    return path
