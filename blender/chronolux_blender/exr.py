"""A small OpenEXR reader (numpy only: Blender bundles it) for the frames Chronolux writes:
scanline files, uncompressed, RLE, ZIPS or ZIP, HALF/FLOAT/UINT channels. It returns
every channel by name, so the beauty (R, G, B[, A]) and the passes Chronolux names as
Blender does (``ViewLayer.<pass>.<channel>``) can be written into the render result.

Blender's own loaders do not do this: ``RenderLayer.load_from_file`` reads only a plain
RGB(A) image, ``RenderResult.load_from_file`` only channels named after the render layer's
existing passes (including ``ViewLayer.Combined.*``, which Chronolux does not write)."""

import struct
import zlib

import numpy as np

_PIXEL_TYPES = {0: (np.uint32, 4), 1: (np.float16, 2), 2: (np.float32, 4)}
_LINES_PER_BLOCK = {0: 1, 1: 1, 2: 1, 3: 16}  # NONE, RLE, ZIPS, ZIP


class ExrError(Exception):
    pass


def _read_attr_value(kind, data):
    if kind == "chlist":
        chans = []
        i = 0
        while i < len(data) and data[i] != 0:
            end = data.index(b"\0", i)
            name = data[i:end].decode("utf-8", "replace")
            ptype, _plinear, xs, ys = struct.unpack_from("<iB3xii", data, end + 1)
            chans.append((name, ptype, xs, ys))
            i = end + 1 + 16
        return chans
    if kind == "box2i":
        return struct.unpack("<iiii", data)
    if kind == "compression":
        return data[0]
    return data


def _unrle(data, expected):
    out = bytearray()
    i, n = 0, len(data)
    while i < n:
        c = struct.unpack_from("b", data, i)[0]
        i += 1
        if c < 0:
            out += data[i:i - c]
            i -= c
        else:
            out += data[i:i + 1] * (c + 1)
            i += 1
    if len(out) != expected:
        raise ExrError("RLE block decodes to %d bytes, not %d" % (len(out), expected))
    return bytes(out)


def _unpredict(raw):
    """Undo OpenEXR's delta predictor and byte interleaving (RLE and ZIP compression)."""
    t = np.frombuffer(raw, dtype=np.uint8).astype(np.int32)
    t = (np.cumsum(t - 128 + (np.arange(t.size) == 0) * 128) & 0xFF).astype(np.uint8)
    half = (t.size + 1) // 2
    out = np.empty(t.size, dtype=np.uint8)
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return out.tobytes()


def read(path):
    """Returns (width, height, {channel name: float32 array of shape (height, width)}),
    rows top first. Raises ExrError for what it cannot read."""
    with open(path, "rb") as f:
        buf = f.read()
    if len(buf) < 8 or struct.unpack_from("<i", buf, 0)[0] != 20000630:
        raise ExrError("%s is not an OpenEXR file" % path)
    version = struct.unpack_from("<i", buf, 4)[0]
    if version & 0x200 or version & 0x1000:
        raise ExrError("%s: tiled or multi-part EXR is not read here" % path)
    pos = 8
    header = {}
    while True:
        end = buf.index(b"\0", pos)
        name = buf[pos:end].decode()
        pos = end + 1
        if not name:
            break
        end = buf.index(b"\0", pos)
        kind = buf[pos:end].decode()
        pos = end + 1
        size = struct.unpack_from("<i", buf, pos)[0]
        pos += 4
        header[name] = _read_attr_value(kind, buf[pos:pos + size])
        pos += size
    try:
        chans = header["channels"]
        x0, y0, x1, y1 = header["dataWindow"]
        comp = header["compression"]
    except KeyError as e:
        raise ExrError("%s: header lacks %s" % (path, e))
    if comp not in _LINES_PER_BLOCK:
        raise ExrError("%s: compression %d is not read here (none, RLE, ZIP)" % (path, comp))
    if any(c[2] != 1 or c[3] != 1 for c in chans):
        raise ExrError("%s: subsampled channels are not read here" % path)
    w, h = x1 - x0 + 1, y1 - y0 + 1
    lpb = _LINES_PER_BLOCK[comp]
    nblocks = (h + lpb - 1) // lpb
    offsets = struct.unpack_from("<%dQ" % nblocks, buf, pos)
    chans = sorted(chans, key=lambda c: c[0])
    line_bytes = sum(_PIXEL_TYPES[c[1]][1] for c in chans) * w
    planes = {c[0]: np.zeros((h, w), dtype=np.float32) for c in chans}
    for off in offsets:
        y, size = struct.unpack_from("<ii", buf, off)
        data = buf[off + 8:off + 8 + size]
        lines = min(lpb, y1 - y + 1)
        expected = line_bytes * lines
        if size < expected:
            if comp == 1:
                data = _unpredict(_unrle(data, expected))
            elif comp in (2, 3):
                data = _unpredict(zlib.decompress(data))
            else:
                raise ExrError("%s: short uncompressed block" % path)
        p = 0
        for line in range(lines):
            row = y - y0 + line
            for name, ptype, _, _ in chans:
                dt, nb = _PIXEL_TYPES[ptype]
                planes[name][row] = np.frombuffer(data, dtype=dt, count=w, offset=p).astype(np.float32)
                p += nb * w
    return w, h, planes
