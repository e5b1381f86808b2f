"""Golden values for the MAT reader's element layout (crates/oddball-io/src/mat/parse.rs): padding and
small data elements as scipy.io.loadmat (1.17.1) reads them.

Writes small MAT files to crates/oddball-io/tests/fixtures/mat/padding/ and, beside them,
padding_golden.json with what scipy reads from each (the same value goldens as make_golden.py's), or the
error scipy raises; tests/mat_padding.rs compares the Rust reader with it.

    python tools/golden/mat/make_padding.py

The rules scipy follows (scipy/io/matlab/_mio5.py `read_var_header`, _mio5_utils.pyx `cread_tag`,
`read_element`):

* a data element's data is followed by padding up to a multiple of 8 bytes, counted from the data's own
  start (`seek(8 - byte_count % 8)`), so a variable that starts at an odd offset keeps odd offsets;
* a small data element (1 to 4 bytes: the byte count in the upper 16 bits of the tag's first word) holds
  its data in the tag's second word: 8 bytes in all;
* a top-level variable (miMATRIX or miCOMPRESSED) ends where its byte count says, with no padding after
  it: MATLAB and scipy write no padding after compressed bytes, so the variable after one starts at any
  offset; padding there, or a top-level byte count that leaves out the padding written after it, is read as
  the next tag and refused.

Files:
* odd_v5.mat — scipy.io.savemat, uncompressed: names of 1 to 9 characters (small elements up to 4, then
  padded), int8/uint8/logical arrays of 1 to 9 values (small elements up to 4 bytes, odd padding after),
  int16/uint16/char of 1 to 5 values (2 to 10 bytes), single and int32 scalars (4-byte small elements),
  complex int8 of 3 values, empty arrays, a struct of odd fields and a cell of odd values;
* odd_v7.mat — the same, each variable a miCOMPRESSED element, back to back with no padding;
* mixed.mat / mixed_be.mat — written byte by byte here, little- and big-endian: a compressed variable
  (of an odd compressed length), then an uncompressed one that therefore starts at an odd offset (a 1x5
  int8 array with a 5-character name, a 1x3 char array, a cell of a 1x3 uint8, a 1x1 double and a 1x7
  int8), then another compressed variable;
* unpadded_top.mat — a top-level variable whose last element (5 bytes) is neither padded nor counted as
  padded, then another variable right after it: scipy reads both;
* count_short_padded.mat — the same variable with the padding written but not counted: scipy refuses;
* compressed_padded.mat — two compressed variables with zero padding to 8 bytes between them: scipy
  refuses;
* trailing_padding.mat — two compressed variables and zero padding to 8 bytes after the last: scipy
  refuses.
"""
from __future__ import annotations

import json
import struct
import sys
import warnings
import zlib
from pathlib import Path

import numpy as np
import scipy
import scipy.io as sio

sys.path.insert(0, str(Path(__file__).resolve().parent))
from make_golden import read_golden  # noqa: E402  (the same value goldens as the main fixtures)

REPO = Path(__file__).resolve().parents[3]
OUT = REPO / "crates/oddball-io/tests/fixtures/mat/padding"

MI = {"int8": 1, "uint8": 2, "int16": 3, "uint16": 4, "int32": 5, "uint32": 6, "double": 9,
      "matrix": 14, "compressed": 15}
CLASS = {"cell": 1, "char": 4, "double": 6, "int8": 8, "uint8": 9}


def odd_variables():
    v = {}
    for n in range(1, 10):
        v["n" * n] = np.array([[n]], dtype=np.uint8)  # names of 1 to 9 characters
        v[f"i8_{n}"] = np.arange(1, n + 1, dtype=np.int8).reshape(1, n) * np.int8(-1) ** n
        v[f"u8_{n}"] = (np.arange(n, dtype=np.uint8) * 31).reshape(n, 1)
        v[f"b_{n}"] = (np.arange(n) % 3 == 0).reshape(1, n)
    for n in range(1, 6):
        v[f"i16_{n}"] = (np.arange(n, dtype=np.int16) - 2) * 1000
        v[f"u16_{n}"] = np.arange(n, dtype=np.uint16) * 9000
        v[f"c_{n}"] = "abcde"[:n]
    v["f32"] = np.array([[-0.375]], dtype=np.float32)
    v["i32"] = np.array([[-7]], dtype=np.int32)
    v["cx8"] = np.array([[1 + 2j, -3 - 4j, 5 + 0j]]).astype(np.complex64)
    v["e_i8"] = np.zeros((0, 3), dtype=np.int8)
    v["e_c"] = np.array([], dtype="U1").reshape(0, 0)
    v["st"] = {"a": np.array([[1, 2, 3]], dtype=np.int8), "bcdef": "xyz",
               "g": np.array([[True]])}
    v["cl"] = np.array([[np.array([[9, 8, 7, 6, 5]], dtype=np.uint8), "q",
                         np.array([[1.5]]), np.zeros((1, 0), dtype=np.int16)]], dtype=object)
    return v


# --- hand-written files -------------------------------------------------------------------------

def element(e: str, mi: int, data: bytes, pad: bool = True) -> bytes:
    """A data element: small (data in the tag) up to 4 bytes, else padded to 8 unless `pad` is
    false."""
    if 0 < len(data) <= 4:
        return struct.pack(e + "I", (len(data) << 16) | mi) + data.ljust(4, b"\0")
    p = (-len(data)) % 8 if pad else 0
    return struct.pack(e + "II", mi, len(data)) + data + b"\0" * p


def matrix(e: str, name: str, cls: str, dims, parts, count_last_pad=True, write_last_pad=True):
    """A miMATRIX element: flags, dims, name, then `parts` ((mi, bytes), or whole elements as
    bytes: nested matrices)."""
    body = element(e, MI["uint32"], struct.pack(e + "II", CLASS[cls], 0))
    body += element(e, MI["int32"], struct.pack(e + "i" * len(dims), *dims))
    body += element(e, MI["int8"], name.encode())
    count_extra = 0
    for k, part in enumerate(parts):
        if isinstance(part, bytes):
            body += part
            continue
        mi, data = part
        last = k == len(parts) - 1
        if last and not write_last_pad:
            body += element(e, mi, data, pad=False)
        elif last and not count_last_pad:
            el = element(e, mi, data, pad=False)
            body += el
            count_extra = (-len(data)) % 8  # written after the counted bytes
        else:
            body += element(e, mi, data)
    return struct.pack(e + "II", MI["matrix"], len(body)) + body + b"\0" * count_extra


def compressed(e: str, m: bytes) -> bytes:
    z = zlib.compress(m)
    return struct.pack(e + "II", MI["compressed"], len(z)) + z


def header(e: str) -> bytes:
    text = b"MATLAB 5.0 MAT-file, written by tools/golden/mat/make_padding.py".ljust(116, b" ")
    return text + b"\0" * 8 + (b"\x01\x00MI" if e == ">" else b"\x00\x01IM")


def mixed(e: str) -> bytes:
    first = compressed(e, matrix(e, "z1", "double", [1, 3], [(MI["int16"], struct.pack(e + "hhh", -1, 0, 300))]))
    # An odd compressed length puts the next variable at an odd offset; retry the payload until it is.
    k = 0
    while (len(header(e)) + len(first)) % 8 in (0, 4):
        k += 1
        first = compressed(e, matrix(e, "z1", "double", [1, 3 + k],
                                     [(MI["int16"], struct.pack(e + "h" * (3 + k), -1, 0, 300, *range(k)))]))
    cell = [
        matrix(e, "", "uint8", [1, 3], [(MI["uint8"], bytes([4, 5, 6]))]),
        matrix(e, "", "double", [1, 1], [(MI["double"], struct.pack(e + "d", 0.125))]),
        matrix(e, "", "int8", [1, 7], [(MI["int8"], bytes([1, 255, 2, 254, 3, 253, 4]))]),
    ]
    plain = matrix(e, "odd_5", "int8", [1, 5], [(MI["int8"], bytes([1, 2, 3, 4, 5]))])
    chars = matrix(e, "ch", "char", [1, 3], [(MI["uint16"], struct.pack(e + "HHH", 0x61, 0x79, 0x7A))])
    cells = matrix(e, "cel", "cell", [1, 3], cell)
    last = compressed(e, matrix(e, "z2", "double", [1, 1], [(MI["double"], struct.pack(e + "d", -2.5))]))
    return header(e) + first + plain + chars + cells + last


def five(e: str, **kw) -> bytes:
    return matrix(e, "five", "int8", [1, 5], [(MI["int8"], bytes([1, 2, 3, 4, 5]))], **kw)


def after(e: str) -> bytes:
    return matrix(e, "next", "double", [1, 1], [(MI["double"], struct.pack(e + "d", 6.5))])


def pad8(b: bytes) -> bytes:
    return b + b"\0" * ((-len(b)) % 8)


def hand_written():
    e = "<"
    z1 = compressed(e, five(e))
    z2 = compressed(e, after(e))
    if len(z1) % 8 == 0 or len(z2) % 8 == 0:
        raise SystemExit("pick payloads whose compressed lengths are not multiples of 8")
    return {
        "mixed.mat": mixed("<"),
        "mixed_be.mat": mixed(">"),
        "unpadded_top.mat": header(e) + five(e, write_last_pad=False) + after(e),
        "count_short_padded.mat": header(e) + five(e, count_last_pad=False) + after(e),
        "compressed_padded.mat": header(e) + pad8(z1) + z2,
        "trailing_padding.mat": header(e) + z1 + pad8(z2),
    }


def scipy_reads(path: Path):
    """What scipy reads, or the error it raises and the offset of the bad tag when it says."""
    try:
        with warnings.catch_warnings():
            # mat_dtype=True casts complex single to its class (the values come from the raw read).
            warnings.simplefilter("ignore", np.exceptions.ComplexWarning)
            return read_golden(path)
    except Exception as ex:  # scipy refuses the file: record how
        return {"error": f"{type(ex).__name__}: {ex}"}


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    v = odd_variables()
    sio.savemat(OUT / "odd_v5.mat", v, format="5", do_compression=False)
    sio.savemat(OUT / "odd_v7.mat", v, format="5", do_compression=True)
    files = ["odd_v5.mat", "odd_v7.mat"]
    for name, b in hand_written().items():
        (OUT / name).write_bytes(b)
        files.append(name)
    # Where scipy's next tag starts in the refused files: after the last variable it could read.
    e = "<"
    z1, z2 = compressed(e, five(e)), compressed(e, after(e))
    bad_tag = {
        "count_short_padded.mat": len(header(e)) + len(five(e, count_last_pad=False)) - 3,
        "compressed_padded.mat": len(header(e)) + len(z1),
        "trailing_padding.mat": len(header(e)) + len(z1) + len(z2),
    }
    gold = {
        "versions": {"scipy": scipy.__version__, "numpy": np.__version__},
        "files": {n: scipy_reads(OUT / n) for n in files},
        "bad_tag_at": bad_tag,
    }
    (OUT / "padding_golden.json").write_text(json.dumps(gold, ensure_ascii=False) + "\n")
    for n in files:
        g = gold["files"][n]
        print(f"{(OUT / n).stat().st_size:6d}  {n}: {g.get('error') or len(g['order'])} ")


if __name__ == "__main__":
    main()
