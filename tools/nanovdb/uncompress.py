#!/usr/bin/env python3
"""Rewrites a NanoVDB file (format version 32) with every grid stored uncompressed (codec NONE):
the fuzzing seeds of neumann's NanoVDB reader (fuzz/run.sh) cover the tree's parsing that way.

    python3 tools/nanovdb/uncompress.py IN.nvdb OUT.nvdb
"""
import struct
import sys
import zlib

SEGMENT_HEADER, META_DATA = 16, 176


def uncompress(data: bytes) -> bytes:
    out, at = bytearray(), 0
    while at < len(data):
        magic, version, count, codec = struct.unpack_from("<QIHH", data, at)
        if magic != 0x304244566F6E614E:
            raise SystemExit(f"no NanoVDB segment at byte {at}")
        out += struct.pack("<QIHH", magic, version, count, 0)
        at += SEGMENT_HEADER
        metas = []
        for _ in range(count):
            meta = bytearray(data[at:at + META_DATA])
            name_size = struct.unpack_from("<I", meta, 136)[0]
            name = data[at + META_DATA:at + META_DATA + name_size]
            at += META_DATA + name_size
            metas.append((meta, name))
        grids = []
        for meta, name in metas:
            grid_size, file_size = struct.unpack_from("<QQ", meta, 0)
            stored = data[at:at + file_size]
            at += file_size
            if codec == 1:
                n = struct.unpack_from("<Q", stored, 0)[0]
                stored = zlib.decompress(stored[8:8 + n])
            elif codec != 0:
                raise SystemExit(f"codec {codec} is not ZIP")
            assert len(stored) == grid_size
            struct.pack_into("<Q", meta, 8, grid_size)
            struct.pack_into("<H", meta, 168, 0)
            out += meta + name
            grids.append(stored)
        for g in grids:
            out += g
    return bytes(out)


if __name__ == "__main__":
    with open(sys.argv[1], "rb") as f:
        data = f.read()
    with open(sys.argv[2], "wb") as f:
        f.write(uncompress(data))
