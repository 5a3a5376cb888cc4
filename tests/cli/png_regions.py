#!/usr/bin/env python3
"""Reads an 8-bit RGB or RGBA PNG (no library needed) and prints what the viewer's checks look at, one
"name value" pair per line: the picture's size, the fraction of pixels that differ from the background (the
top-left pixel's colour), and for the region colours of the viewer (handle 0 red, fixed slate blue) the
pixel count and centroid.

usage: png_regions.py FILE.png"""
import struct
import sys
import zlib


def read_png(path):
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        sys.exit(f"{path}: not a PNG")
    pos, idat, width = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, color, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or color not in (2, 6) or interlace:
                sys.exit(f"{path}: only 8-bit RGB/RGBA, non-interlaced PNGs are read")
            channels = 3 if color == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw, stride = zlib.decompress(idat), width * channels
    rows, previous = [], bytearray(stride)
    for y in range(height):
        kind, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b, c = previous[i], previous[i - channels] if i >= channels else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        previous = line
    return width, height, channels, rows


def main():
    width, height, channels, rows = read_png(sys.argv[1])
    background = tuple(rows[0][:3])
    drawn = 0
    classes = {"handle": [0, 0, 0], "fixed": [0, 0, 0]}
    for y, line in enumerate(rows):
        for x in range(width):
            r, g, b = line[x * channels:x * channels + 3]
            if max(abs(r - background[0]), abs(g - background[1]), abs(b - background[2])) > 12:
                drawn += 1
            kind = "handle" if r > 2 * g and r > 2 * b and r > 60 else "fixed" if b > 1.3 * r and b > 1.1 * g and b > 60 else None
            if kind:
                classes[kind][0] += 1
                classes[kind][1] += x
                classes[kind][2] += y
    print("size", width, height)
    print("drawn", round(drawn / (width * height), 4))
    for name, (n, sx, sy) in classes.items():
        print(name + "_pixels", n)
        print(name + "_centroid", round(sx / n, 1) if n else -1, round(sy / n, 1) if n else -1)


main()
