"""A small PNG reader for the report tests (8-bit greyscale, RGB or RGBA, not interlaced: what
Chromium's --screenshot writes), without PIL. Returns a numpy array of shape (H, W, 3), uint8."""
import struct
import zlib

import numpy as np


def _paeth_row(line, prev, bpp):
    out = bytearray(line)
    for x in range(len(out)):
        a = out[x - bpp] if x >= bpp else 0
        b = prev[x]
        c = prev[x - bpp] if x >= bpp else 0
        p = a + b - c
        pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
        pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
        out[x] = (out[x] + pred) & 0xFF
    return out


def _average_row(line, prev, bpp):
    out = bytearray(line)
    for x in range(len(out)):
        a = out[x - bpp] if x >= bpp else 0
        out[x] = (out[x] + ((a + prev[x]) >> 1)) & 0xFF
    return out


def read_png(path):
    data = open(path, 'rb').read()
    if data[:8] != b'\x89PNG\r\n\x1a\n':
        raise ValueError('%s: not a PNG file' % path)
    pos, idat, header = 8, [], None
    while pos < len(data):
        length, kind = struct.unpack('>I4s', data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b'IHDR':
            header = struct.unpack('>IIBBBBB', body)
        elif kind == b'IDAT':
            idat.append(body)
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    channels = {0: 1, 2: 3, 6: 4}.get(colour)
    if depth != 8 or channels is None or interlace:
        raise ValueError('%s: unsupported PNG (depth %d, colour type %d, interlace %d)'
                         % (path, depth, colour, interlace))
    raw = zlib.decompress(b''.join(idat))
    stride = width * channels
    rows = np.zeros((height, stride), dtype=np.uint8)
    prev = np.zeros(stride, dtype=np.uint8)
    for y in range(height):
        start = y * (stride + 1)
        kind = raw[start]
        line = np.frombuffer(raw, dtype=np.uint8, count=stride, offset=start + 1)
        if kind == 0:
            cur = line.copy()
        elif kind == 1:  # Sub: a running sum per channel
            cur = (np.cumsum(line.reshape(width, channels).astype(np.uint32), axis=0) & 0xFF)
            cur = cur.astype(np.uint8).reshape(stride)
        elif kind == 2:
            cur = (line.astype(np.uint16) + prev).astype(np.uint8)
        elif kind == 3:
            cur = np.frombuffer(bytes(_average_row(line.tobytes(), prev.tobytes(), channels)), np.uint8)
        elif kind == 4:
            cur = np.frombuffer(bytes(_paeth_row(line.tobytes(), prev.tobytes(), channels)), np.uint8)
        else:
            raise ValueError('%s: bad PNG filter %d' % (path, kind))
        rows[y] = cur
        prev = cur
    image = rows.reshape(height, width, channels)
    if channels == 1:
        image = np.repeat(image, 3, axis=2)
    return image[:, :, :3]
