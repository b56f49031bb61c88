"""A PNG and APNG reader written from the specifications (standard library only), independent of
evray's writer (libpng under src/io/apng.c): every chunk's CRC and order checked, every frame
inflated and unfiltered. 8-bit gray, RGB and RGBA, not interlaced (what evray writes).

  read(path) -> (width, height, channels, frames, delays): frames as bytes, rows top first;
      delays in seconds per frame (a plain PNG: one frame, delay None). Raises ValueError
      naming what is wrong.
  write_png(path, width, height, channels, pixels): one 8-bit image (for docs pictures).

`python3 tests/apng_read.py FILE.apng K OUT.png` writes frame K of an APNG as a PNG.
"""
import struct
import sys
import zlib

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _chunks(data):
    if not data.startswith(SIGNATURE):
        raise ValueError("not a PNG signature")
    at = 8
    while at < len(data):
        if at + 12 > len(data):
            raise ValueError(f"a chunk cut short at byte {at}")
        n, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + n]
        if len(body) != n or at + 12 + n > len(data):
            raise ValueError(f"chunk {kind!r} at byte {at} runs past the end")
        crc = struct.unpack(">I", data[at + 8 + n:at + 12 + n])[0]
        if zlib.crc32(kind + body) & 0xFFFFFFFF != crc:
            raise ValueError(f"chunk {kind!r} at byte {at}: bad CRC")
        yield kind, body
        at += 12 + n


def _unfilter(raw, width, height, bpp):
    stride = width * bpp
    if len(raw) != height * (stride + 1):
        raise ValueError(f"image data of {len(raw)} bytes, expected {height * (stride + 1)}")
    out = bytearray(height * stride)
    prev = bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b = prev[x]
            c = prev[x - bpp] if x >= bpp else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[x] = (line[x] + pred) & 255
            elif f != 0:
                raise ValueError(f"unknown filter {f} in row {y}")
        out[y * stride:(y + 1) * stride] = line
        prev = line
    return bytes(out)


def read(path):
    with open(path, "rb") as fh:
        data = fh.read()
    chunks = list(_chunks(data))
    if not chunks or chunks[0][0] != b"IHDR":
        raise ValueError("the first chunk is not IHDR")
    if chunks[-1][0] != b"IEND":
        raise ValueError("the last chunk is not IEND")
    width, height, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", chunks[0][1])
    channels = {0: 1, 2: 3, 6: 4}.get(ctype)
    if depth != 8 or channels is None or interlace:
        raise ValueError(f"unsupported PNG: depth {depth}, colour type {ctype}, interlace {interlace}")
    actl = None
    frames, delays, current = [], [], None  # current: the frame's zlib data being gathered
    seq = 0
    idat_seen = False
    for kind, body in chunks[1:-1]:
        if kind == b"acTL":
            if idat_seen:
                raise ValueError("acTL after the image data")
            actl = struct.unpack(">II", body)
        elif kind == b"fcTL":
            n, w, h, x0, y0, dn, dd, dispose, blend = struct.unpack(">IIIIIHHBB", body)
            if n != seq:
                raise ValueError(f"fcTL sequence number {n}, expected {seq}")
            seq += 1
            if (w, h, x0, y0) != (width, height, 0, 0):
                raise ValueError("a frame that is not the whole image")
            if current is not None:
                frames.append(current)
            current = bytearray()
            delays.append(dn / (dd or 100))
        elif kind == b"IDAT":
            idat_seen = True
            if actl is not None and len(frames) + (current is not None) != 1:
                raise ValueError("IDAT outside frame 0")
            if current is None:  # a plain PNG, or an APNG whose default image is no frame
                current = bytearray()
            current += body
        elif kind == b"fdAT":
            n = struct.unpack(">I", body[:4])[0]
            if n != seq:
                raise ValueError(f"fdAT sequence number {n}, expected {seq}")
            seq += 1
            if current is None or not idat_seen:
                raise ValueError("fdAT before the first frame")
            current += body[4:]
    if current is not None:
        frames.append(current)
    if actl is not None and actl[0] != len(frames):
        raise ValueError(f"acTL says {actl[0]} frames, the file has {len(frames)}")
    images = [_unfilter(zlib.decompress(bytes(f)), width, height, channels) for f in frames]
    return width, height, channels, images, (delays if actl is not None else [None])


def write_png(path, width, height, channels, pixels):
    stride = width * channels
    raw = b"".join(b"\0" + pixels[y * stride:(y + 1) * stride] for y in range(height))

    def chunk(kind, body):
        return (struct.pack(">I", len(body)) + kind + body +
                struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))

    ctype = {1: 0, 3: 2, 4: 6}[channels]
    with open(path, "wb") as fh:
        fh.write(SIGNATURE + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, ctype, 0, 0, 0)) +
                 chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


if __name__ == "__main__":
    w, h, c, frames, _ = read(sys.argv[1])
    write_png(sys.argv[3], w, h, c, frames[int(sys.argv[2])])
