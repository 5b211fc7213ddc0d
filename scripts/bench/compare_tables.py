#!/usr/bin/env python3
"""Compares two `sora tables` directories: files byte for byte, and where an
EXR file differs (scanline, no or ZIP/ZIPS compression, 32-bit float
channels) how many values differ and the largest relative difference.
Python standard library only.

    python3 scripts/bench/compare_tables.py OLD_DIR NEW_DIR
"""
import sys, os, struct, zlib, array, math

def read_header(b):
    assert b[:4] == b'\x76\x2f\x31\x01'
    p = 8; attrs = {}
    while b[p] != 0:
        e = b.index(b'\0', p); name = b[p:e].decode(); p = e + 1
        e = b.index(b'\0', p); typ = b[p:e].decode(); p = e + 1
        size, = struct.unpack_from('<i', b, p); p += 4
        attrs[name] = (typ, b[p:p+size]); p += size
    return attrs, p + 1

def channels(raw):
    out = []; p = 0
    while raw[p] != 0:
        e = raw.index(b'\0', p); name = raw[p:e].decode(); p = e + 1
        pt, = struct.unpack_from('<i', raw, p); p += 16
        out.append((name, pt))
    return out

def undo(data):
    t = bytearray(data)
    for i in range(1, len(t)):
        t[i] = (t[i-1] + t[i] - 128) & 0xff
    h = (len(t) + 1) // 2
    out = bytearray(len(t))
    out[0::2] = t[:h]; out[1::2] = t[h:]
    return bytes(out)

def read_exr(path):
    b = open(path, 'rb').read()
    attrs, p = read_header(b)
    chans = channels(attrs['channels'][1])
    comp = attrs['compression'][1][0]
    xmin, ymin, xmax, ymax = struct.unpack('<4i', attrs['dataWindow'][1])
    w, h = xmax - xmin + 1, ymax - ymin + 1
    lines = {0: 1, 2: 1, 3: 16}[comp]
    nchunks = (h + lines - 1) // lines
    offsets = struct.unpack_from('<%dQ' % nchunks, b, p)
    vals = {c: array.array('f') for c, _ in chans}
    for off in offsets:
        y, size = struct.unpack_from('<ii', b, off)
        data = b[off+8:off+8+size]
        n = min(lines, ymax + 1 - y)
        expect = n * w * 4 * len(chans)
        if comp != 0 and size < expect:
            data = undo(zlib.decompress(data))
        q = 0
        for _ in range(n):
            for c, pt in chans:
                assert pt == 2
                vals[c].frombytes(data[q:q + 4 * w]); q += 4 * w
    return vals

def main(a, b):
    worst_all = 0.0
    for f in sorted(os.listdir(a)):
        pa, pb = os.path.join(a, f), os.path.join(b, f)
        ba, bb = open(pa, 'rb').read(), open(pb, 'rb').read()
        if ba == bb:
            print(f'{f}: identical bytes'); continue
        if not f.endswith('.exr'):
            print(f'{f}: bytes differ ({len(ba)} vs {len(bb)})'); continue
        va, vb = read_exr(pa), read_exr(pb)
        for c in va:
            xa, xb = va[c], vb[c]
            assert len(xa) == len(xb)
            peak = max(abs(v) for v in xa)
            worst, worst_abs, ndiff = 0.0, 0.0, 0
            for u, v in zip(xa, xb):
                if u != v:
                    ndiff += 1
                    d = abs(u - v)
                    m = max(abs(u), abs(v))
                    worst = max(worst, d / m)
                    worst_abs = max(worst_abs, d / peak if peak else d)
            worst_all = max(worst_all, worst)
            print(f'{f} {c}: {ndiff} of {len(xa)} values differ, largest relative {worst:.3g}, largest relative to the channel peak {worst_abs:.3g}')
    print(f'largest relative difference {worst_all:.3g}')

main(sys.argv[1], sys.argv[2])
