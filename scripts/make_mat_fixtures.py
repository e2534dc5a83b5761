#!/usr/bin/env python3
"""Write the MATLAB .mat fixtures of src/campaign/matlab (tests/data/matlab/).

Run with the project venv: `.venv/bin/python scripts/make_mat_fixtures.py`.
The files are committed (a few kB each) so the Rust tests need no Python.
Every value here is asserted exactly by the unit tests in src/campaign/matlab/tests.rs.
"""
import struct
from pathlib import Path

import numpy as np
import scipy.io
import scipy.sparse

OUT = Path(__file__).resolve().parent.parent / "tests" / "data" / "matlab"

# Level-5 tags (MathWorks "MAT-File Format", table 1-1 and 1-3).
MI_INT8, MI_UINT8, MI_INT16, MI_INT32, MI_UINT32, MI_DOUBLE = 1, 2, 3, 5, 6, 9
MI_UINT16, MI_MATRIX = 4, 14
MX_CHAR, MX_DOUBLE = 4, 6


def plain_variables():
    """accel[k] = sin(0.1 k); data[i, j] = 100 (j + 1) + i + 0.25; counts int16; label char."""
    k = np.arange(100)
    i = np.arange(50)[:, None]
    j = np.arange(3)[None, :]
    return {
        "accel": np.sin(0.1 * k),  # 1 x 100 (scipy writes 1-D as a row)
        "data": 100.0 * (j + 1) + i + 0.25,  # 50 x 3
        "counts": (np.arange(-5, 5) * 1000).astype(np.int16),
        "label": "Xgf table displacement",
        "notes": np.array([["first", np.array([[1.0, 2.0, 3.0]])]], dtype=object),
        "z": np.array([1 + 2j, 3 - 4j]),
        "sp": scipy.sparse.csc_matrix(np.eye(3)),
    }


def dspace_recording():
    """A ControlDesk-like recording `rec`: X = time, Y(1..3) = signals (Xgf twice, other paths)."""
    k = np.arange(200)
    t = k / 1000.0
    x = {"Name": "Time", "Type": "double", "Data": t[None, :], "Unit": "s"}
    y = np.zeros((1, 3), dtype=[("Name", "O"), ("Type", "O"), ("Path", "O"),
                                ("Data", "O"), ("Unit", "O"), ("Extra", "O")])
    rows = [("Xgf", "Model Root/Plant", 0.01 * np.cos(0.05 * k), "m"),
            ("Agf", "Model Root/Plant", 0.5 * k, "m/s^2"),
            ("Xgf", "Model Root/Controller", -1.0 * k, "V")]
    for n, (name, path, data, unit) in enumerate(rows):
        y[0, n] = (name, "double", path, data[None, :], unit, np.zeros((0, 0)))
    return {"rec": {"X": x, "Y": y, "Description": "shaketable fixture"}}


def dspace_two_rasters():
    """A recording with two time bases: X(1) at 1 kHz (100 samples), X(2) at 100 Hz (10);
    Y(i).XIndex says which one each signal follows. Written uncompressed."""
    x = np.zeros((1, 2), dtype=[("Name", "O"), ("Data", "O"), ("Unit", "O")])
    x[0, 0] = ("Time", (np.arange(100) / 1000.0)[None, :], "s")
    x[0, 1] = ("Time", (np.arange(10) / 100.0)[None, :], "s")
    y = np.zeros((1, 2), dtype=[("Name", "O"), ("Path", "O"), ("Data", "O"), ("XIndex", "O")])
    y[0, 0] = ("Fast", "Model Root", np.arange(100.0)[None, :], 1.0)
    y[0, 1] = ("Slow", "Model Root", -np.arange(10.0)[None, :], 2.0)
    return {"rasters": {"X": x, "Y": y}}


def element(endian, mi_type, payload):
    """One data element, small format when it fits in 4 bytes, padded to 8 bytes."""
    if len(payload) <= 4 and mi_type != MI_MATRIX:
        return struct.pack(endian + "I", (len(payload) << 16) | mi_type) + payload.ljust(4, b"\0")
    pad = (-len(payload)) % 8
    return struct.pack(endian + "II", mi_type, len(payload)) + payload + b"\0" * pad


def matrix(endian, mx_class, name, dims, data_type, data_fmt, values):
    """An uncompressed miMATRIX as MATLAB writes it: flags, dims, name, real part."""
    body = element(endian, MI_UINT32, struct.pack(endian + "II", mx_class, 0))
    body += element(endian, MI_INT32, struct.pack(endian + "%di" % len(dims), *dims))
    body += element(endian, MI_INT8, name.encode())
    body += element(endian, data_type, struct.pack(endian + "%d%s" % (len(values), data_fmt), *values))
    return element(endian, MI_MATRIX, body)


def header(text, version, endian_mark):
    return text.ljust(116, b" ") + b"\0" * 8 + version + endian_mark


def hand_written(endian):
    """MATLAB-style storage: doubles stored as miINT16 / miUINT8 when they fit, chars as miUINT16."""
    mark = b"MI" if endian == ">" else b"IM"
    version = struct.pack(endian + "H", 0x0100)
    out = header(b"MATLAB 5.0 MAT-file, hand-written by make_mat_fixtures.py", version, mark)
    out += matrix(endian, MX_DOUBLE, "accel_be", [3, 1], MI_DOUBLE, "d", [1.5, -2.25, 3.0])
    out += matrix(endian, MX_DOUBLE, "small", [1, 3], MI_INT16, "h", [1, -2, 300])
    out += matrix(endian, MX_DOUBLE, "bytes", [1, 2], MI_UINT8, "B", [7, 255])
    out += matrix(endian, MX_CHAR, "unit", [1, 4], MI_UINT16, "H", [ord(c) for c in "m/s2"])
    return out


def v73_stub():
    """The first bytes of a v7.3 file: its header text and the HDF5 signature at byte 512."""
    out = header(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 .",
                 struct.pack("<H", 0x0200), b"IM")
    out = out.ljust(512, b"\0")
    return out + b"\x89HDF\r\n\x1a\n" + b"\0" * 24


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    scipy.io.savemat(OUT / "plain.mat", plain_variables())
    scipy.io.savemat(OUT / "plain_z.mat", plain_variables(), do_compression=True)
    scipy.io.savemat(OUT / "v4.mat", {"accel": np.sin(0.1 * np.arange(10))}, format="4")
    scipy.io.savemat(OUT / "dspace.mat", dspace_recording(), do_compression=True)
    scipy.io.savemat(OUT / "dspace_rasters.mat", dspace_two_rasters())
    (OUT / "bigendian.mat").write_bytes(hand_written(">"))
    (OUT / "littleendian.mat").write_bytes(hand_written("<"))
    (OUT / "v73.mat").write_bytes(v73_stub())
    # Check the hand-written files with scipy's own reader.
    for name in ("bigendian.mat", "littleendian.mat"):
        m = scipy.io.loadmat(OUT / name)
        assert np.array_equal(m["accel_be"].ravel(), [1.5, -2.25, 3.0]), name
        assert np.array_equal(m["small"].ravel(), [1, -2, 300]), name
        assert m["unit"][0] == "m/s2", name
    for p in sorted(OUT.glob("*.mat")):
        print(f"{p.name}: {p.stat().st_size} bytes")


if __name__ == "__main__":
    main()
