"""Seeded mutations of data files, for the fuzz tests (and a larger campaign by hand).

Every mutator takes the file's bytes and a ``random.Random`` and returns new bytes:
truncations, token swaps, absurd finite values, wrong counts (lines dropped or doubled),
binary junk, other encodings, case changes, degenerate geometry. A test writes the
result to a file, reads it the way the command line does, and asserts the outcome is a
clean result or one :class:`upm.core.errors.DataFileError` naming that file.
"""

from __future__ import annotations

import io
import random
import re
import zipfile

import numpy as np

#: Finite numbers no real file holds, and numbers that are not plain ASCII decimals.
ABSURD_NUMBERS = ("1e300", "-1e308", "1e308", "5e-324", "-0", "0", "1e-300", "1e6", "1e7",
                  "123456789012345678901234567890", "9" * 5000, "\u00b2", "\u00b3", "\u00b9",
                  "\u0661", "1_000", "0x10", "inf", "nan", "-", "1e")
_NUMBER = re.compile(rb"-?\d+(?:\.\d*)?(?:e[-+]?\d+)?", re.IGNORECASE)


def _lines(data: bytes) -> list[bytes]:
    return data.split(b"\n")


def truncate(data: bytes, rng: random.Random) -> bytes:
    return data[:rng.randrange(len(data))]


def swap_tokens(data: bytes, rng: random.Random) -> bytes:
    tokens = re.split(rb"(\s+)", data)
    words = [i for i, t in enumerate(tokens) if t and not t.isspace()]
    if len(words) < 2:
        return data
    i, j = rng.sample(words, 2)
    tokens[i], tokens[j] = tokens[j], tokens[i]
    return b"".join(tokens)


def absurd_number(data: bytes, rng: random.Random) -> bytes:
    numbers = list(_NUMBER.finditer(data))
    if not numbers:
        return data
    value = rng.choice(ABSURD_NUMBERS).encode("utf-8")
    for match in rng.sample(numbers, min(len(numbers), rng.choice((1, 1, 3, 50)))):
        data = data[:match.start()] + value + data[match.end():] if len(
            data) > match.end() else data
        numbers = list(_NUMBER.finditer(data))
        if not numbers:
            break
    return data


def all_numbers(data: bytes, rng: random.Random) -> bytes:
    """Every number of a random stretch of lines replaced by one absurd value."""
    value = rng.choice(("1e300", "1e308", "-1e300", "0")).encode()
    lines = _lines(data)
    a = rng.randrange(len(lines))
    b = min(len(lines), a + rng.randrange(1, 60))
    lines[a:b] = [_NUMBER.sub(value, line) for line in lines[a:b]]
    return b"\n".join(lines)


def drop_line(data: bytes, rng: random.Random) -> bytes:
    lines = _lines(data)
    del lines[rng.randrange(len(lines))]
    return b"\n".join(lines)


def double_line(data: bytes, rng: random.Random) -> bytes:
    lines = _lines(data)
    i = rng.randrange(len(lines))
    lines.insert(i, lines[i])
    return b"\n".join(lines)


def drop_token(data: bytes, rng: random.Random) -> bytes:
    lines = _lines(data)
    i = rng.randrange(len(lines))
    tokens = lines[i].split()
    if tokens:
        del tokens[rng.randrange(len(tokens))]
        lines[i] = b" ".join(tokens)
    return b"\n".join(lines)


def binary_junk(data: bytes, rng: random.Random) -> bytes:
    at = rng.randrange(len(data))
    junk = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 64)))
    return data[:at] + junk + data[at:]


def reencode(data: bytes, rng: random.Random) -> bytes:
    choice = rng.randrange(4)
    if choice == 0:
        return data.decode("latin-1").encode("utf-16")
    if choice == 1:
        at = rng.randrange(len(data))
        return data[:at] + b"\xff\xfe\xc3" + data[at:]
    if choice == 2:
        return b"\xef\xbb\xbf" + data.replace(b"\n", b"\r\n")
    return data.replace(b"\n", b"\r")


def change_case(data: bytes, rng: random.Random) -> bytes:
    lines = _lines(data)
    i = rng.randrange(len(lines))
    lines[i] = lines[i].upper() if rng.random() < 0.5 else lines[i].lower()
    return b"\n".join(lines)


def huge_field(data: bytes, rng: random.Random) -> bytes:
    at = rng.randrange(len(data))
    return data[:at] + b"x" * rng.choice((1000, 200_000, 1_100_000)) + data[at:]


def degenerate_bone(data: bytes, rng: random.Random) -> bytes:
    """An ASF bone of length 0 (or -0, or 1e-300), or with direction 0 0 0."""
    lines = _lines(data)
    which = [i for i, line in enumerate(lines)
             if line.strip().startswith((b"length", b"direction"))]
    if not which:
        return data
    i = rng.choice(which)
    key = lines[i].split()[0]
    if key == b"length":
        lines[i] = b"length " + rng.choice((b"0", b"-0", b"1e-300", b"1e300", b"1e308"))
    else:
        lines[i] = b"direction 0 0 0"
    return b"\n".join(lines)


TEXT_MUTATORS = (truncate, swap_tokens, absurd_number, all_numbers, drop_line, double_line,
                 drop_token, binary_junk, reencode, change_case)
ASF_MUTATORS = (*TEXT_MUTATORS, degenerate_bone, degenerate_bone)
CSV_MUTATORS = (*TEXT_MUTATORS, huge_field)


def mutate(data: bytes, rng: random.Random, mutators=TEXT_MUTATORS, rounds: int = 0) -> bytes:
    """``data`` after 1 to 3 (or ``rounds``) random mutations."""
    for _ in range(rounds or rng.choice((1, 1, 1, 2, 3))):
        if len(data) < 2:
            break
        data = rng.choice(mutators)(data, rng)
    return data


# -- map archives ----------------------------------------------------------------------

def mutate_npz(data: bytes, rng: random.Random) -> bytes:
    """A saved map's archive with one member damaged, replaced, removed or bombed, or
    the archive's bytes flipped or truncated."""
    import numpy as np

    choice = rng.choice((0, 1, 2, 3, 4, 5, 7))
    if choice == 0:
        out = bytearray(data)
        for _ in range(rng.choice((1, 4, 32))):
            out[rng.randrange(len(out))] ^= 1 << rng.randrange(8)
        return bytes(out)
    if choice == 1:
        return data[:rng.randrange(len(data))]
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        members = {i.filename: archive.read(i) for i in archive.infolist()}
    name = rng.choice(sorted(members))
    if choice == 2:
        del members[name]
    elif choice == 3:  # raw bytes instead of an .npy, or a name without .npy
        members[name[:-4] if rng.random() < 0.5 else name] = bytes(
            rng.randrange(256) for _ in range(rng.randrange(1, 200)))
    elif choice == 4:  # another array: 0-d, wrong rank, dtype, or an object array
        value = rng.choice((np.array("body"), np.zeros(3), np.zeros((2, 2, 2)),
                            np.array([1, 2], dtype=np.int8), np.array(["a", "b"]),
                            np.array(1.5), None, np.full((3, 15), 1e308), np.zeros((0, 15))))
        if value is None:  # an object array: header only, its payload is never unpickled
            members[name] = object_npy(b"\x80\x04junk")
        else:
            buffer = io.BytesIO()
            np.lib.format.write_array(buffer, value)
            members[name] = buffer.getvalue()
    elif choice == 5:  # metadata edits
        meta = rng.choice(('{"params": {}, "stats": {"body": null}, "provenance": {}}',
                           '{"params": [], "stats": [], "provenance": []}',
                           '[1, 2]', '{"params": {"radius_deg": "x"}, "stats": {}, '
                           '"provenance": {}}', "\u00ff" * 10))
        buffer = io.BytesIO()
        np.lib.format.write_array(buffer, np.array(meta))
        members["meta_json.npy"] = buffer.getvalue()
    else:
        members[name] = members[name][:rng.randrange(len(members[name]))]
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as archive:
        for key, value in members.items():
            archive.writestr(key, value)
    return out.getvalue()


def object_npy(payload: bytes, length: int = 1) -> bytes:
    """An ``.npy`` member declaring an object array (``|O``) followed by ``payload``: what a
    pickle-bearing map looks like, written without pickling anything."""
    buffer = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        buffer, {"descr": "|O", "fortran_order": False, "shape": (length,)})
    return buffer.getvalue() + payload


def zip_bomb(data: bytes, megabytes: int = 64) -> bytes:
    """The archive plus a member of ``megabytes`` MB of zeros (about 1000:1 compressed)."""
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        members = {i.filename: archive.read(i) for i in archive.infolist()}
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as archive:
        for key, value in members.items():
            archive.writestr(key, value)
        with archive.open("neurons_body.npy" if "neurons_body.npy" not in members
                          else "bomb.npy", "w", force_zip64=True) as member:
            block = bytes(1 << 20)
            for _ in range(megabytes):
                member.write(block)
    return out.getvalue()
