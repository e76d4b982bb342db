"""Renders the built-in Cornell box with neumann's three solvers of the rendering equation —
backward path tracing, forward light tracing (ptracer) and radiosity — and writes them side by
side as one PNG (docs/images/cbox_solvers.png), printing the time each took.

Run from the repository root after `cargo build --release`:
    python3 tools/solvers_sheet.py
Standard library only (PFM in, PNG out)."""
import os
import re
import struct
import subprocess
import tempfile
import zlib

RES = 160
SOLVERS = [
    ("path", ["--integrator", "path", "--spp", "256"]),
    ("ptracer", ["--integrator", "ptracer", "--spp", "256"]),
    ("radiosity", ["--integrator", "radiosity", "--patch-size", "0.05", "--ff-rays", "1024", "--smooth", "--spp", "16"]),
]
GAP = 4


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        fmt = "<" if scale < 0 else ">"
        data = struct.unpack(fmt + "f" * (w * h * 3), f.read(w * h * 12))
    # PFM rows run bottom to top.
    rows = [data[(h - 1 - y) * w * 3:(h - y) * w * 3] for y in range(h)]
    return w, h, rows


def srgb(v):
    v = min(max(v, 0.0), 1.0)
    v = 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
    return int(round(v * 255))


def write_png(path, w, h, rows):
    raw = b"".join(b"\x00" + bytes(r) for r in rows)
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def main():
    panels = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, args in SOLVERS:
            out = os.path.join(tmp, name + ".pfm")
            cmd = ["target/release/neumann", "render", "--res", str(RES), "--quiet", "-o", out] + args
            text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
            seconds = float(re.search(r"([0-9.]+) s,", text).group(1))
            print(f"{name}: {seconds:.2f} s  ({' '.join(args)})")
            panels.append(read_pfm(out))
    h = panels[0][1]
    width = sum(p[0] for p in panels) + GAP * (len(panels) - 1)
    rows = []
    for y in range(h):
        row = []
        for k, (w, _, img) in enumerate(panels):
            row += [srgb(v) for v in img[y]]
            if k + 1 < len(panels):
                row += [255] * (3 * GAP)
        rows.append(row)
    os.makedirs("docs/images", exist_ok=True)
    write_png("docs/images/cbox_solvers.png", width, h, rows)
    print("wrote docs/images/cbox_solvers.png")


if __name__ == "__main__":
    main()
