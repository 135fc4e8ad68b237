"""A minimal PNG reader for the browser test's screenshots (8-bit RGB/RGBA, not interlaced):
the test dependencies have no image library."""

from __future__ import annotations

import struct
import zlib

import numpy as np

SIGNATURE = b"\x89PNG\r\n\x1a\n"
CHANNELS = {0: 1, 2: 3, 4: 2, 6: 4}  # colour type -> samples per pixel


def read_png(data: bytes, rows: int | None = None) -> np.ndarray:
    """The image as (height, width, channels) uint8; only the first ``rows`` rows if given
    (each row's filter needs the one above, so a prefix is cheap to decode)."""
    if data[:8] != SIGNATURE:
        raise ValueError("not a PNG file")
    pos, chunks, header = 8, [], None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind, body = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            chunks.append(body)
        elif kind == b"IEND":
            break
    if header is None:
        raise ValueError("PNG without IHDR")
    width, height, depth, colour, _, _, interlace = header
    if depth != 8 or interlace or colour not in CHANNELS:
        raise ValueError(f"unsupported PNG: depth {depth}, colour type {colour}, interlace")
    bpp = CHANNELS[colour]
    stride = width * bpp
    raw = zlib.decompress(b"".join(chunks))
    n = height if rows is None else min(rows, height)
    out = np.zeros((n, stride), dtype=np.uint8)
    prev = np.zeros(stride, dtype=np.int64)
    for y in range(n):
        start = y * (stride + 1)
        line = np.frombuffer(raw, np.uint8, stride, start + 1).astype(np.int64)
        cur = _unfilter(raw[start], line, prev, bpp)
        out[y] = cur
        prev = cur
    return out.reshape(n, width, bpp)


def _unfilter(kind: int, line: np.ndarray, prev: np.ndarray, bpp: int) -> np.ndarray:
    if kind == 0:
        return line
    if kind == 1:  # Sub: a running sum per channel
        return line.reshape(-1, bpp).cumsum(axis=0).ravel() & 0xFF
    if kind == 2:  # Up
        return (line + prev) & 0xFF
    cur = bytearray(len(line))
    raw, up = line.tolist(), prev.tolist()
    for x in range(len(raw)):
        a = cur[x - bpp] if x >= bpp else 0
        b = up[x]
        if kind == 3:  # Average
            cur[x] = (raw[x] + ((a + b) >> 1)) & 0xFF
            continue
        c = up[x - bpp] if x >= bpp else 0  # Paeth
        p = a + b - c
        pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
        pred = a if pa <= pb and pa <= pc else b if pb <= pc else c
        cur[x] = (raw[x] + pred) & 0xFF
    return np.frombuffer(bytes(cur), dtype=np.uint8).astype(np.int64)
