"""checklib: the pass/fail bookkeeping shared by clvr's Python test scripts.

A script does `check = Checks()`, calls `check(ok, what, got, want)` for each
assertion (a failure prints what was got and wanted) and ends with
`check.summary()`, whose "N passed, N failed" line ctest's log shows."""


class Checks:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def __call__(self, ok, what, got=None, want=None):
        if ok:
            self.passed += 1
        else:
            self.failed += 1
            extra = f": got {got!r}, want {want!r}" if got is not None or want is not None else ""
            print(f"FAIL {what}{extra}")
        return ok

    def summary(self):
        print(f"{self.passed} passed, {self.failed} failed")


def read_pfm(path):
    """Reads a PFM (what clvr writes for -o x.pfm): returns (width, height,
    data), data the floats as stored, rows bottom to top, 3 per pixel for a
    colour PFM (PF), 1 for a grey one (Pf)."""
    import struct

    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        n = w * h * (3 if kind == b"PF" else 1)
        data = struct.unpack(("<" if scale < 0 else ">") + "%df" % n, f.read(4 * n))
    return w, h, data


def read_png(path):
    """Decodes an 8-bit, non-interlaced grey/RGB/RGBA PNG (what clvr writes)
    without third-party modules: returns (width, height, channels, rows), rows
    a list of bytes objects of width * channels samples."""
    import struct
    import zlib

    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path}: not a PNG")
    pos, idat, hdr = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            hdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    w, h, depth, ctype, _, _, interlace = hdr
    ch = {0: 1, 2: 3, 4: 2, 6: 4}.get(ctype)
    if depth != 8 or ch is None or interlace:
        raise ValueError(f"{path}: unsupported PNG (depth {depth}, colour type {ctype}, interlace {interlace})")
    raw, stride, rows, prev = zlib.decompress(idat), w * ch, [], bytearray(w * ch)
    for y in range(h):
        ftype, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - ch] if i >= ch else 0
            b, c = prev[i], prev[i - ch] if i >= ch else 0
            if ftype == 1:
                line[i] = (line[i] + a) & 255
            elif ftype == 2:
                line[i] = (line[i] + b) & 255
            elif ftype == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif ftype == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return w, h, ch, rows
