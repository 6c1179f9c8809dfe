#!/usr/bin/env python3
"""Regenerate the X-toon threshold maps in samples/maps/ (Python 3 standard library only).

Writes 16-bit PNGs; README.md gives the oiiotool line that turns them into the EXRs the sample
graphs use. Every map is 256 x 64: columns are the pattern axis u (0 left, 1 right), rows the
tone axis v (0 bottom, 1 top), the orientation the threshold-map node reads (see its help).
Values are data in [0,1], not sRGB-encoded colours.

    python3 samples/maps/make_maps.py samples/maps
"""
import functools
import math
import os
import struct
import sys
import zlib

W, H = 256, 64


def threshold(p, sigma, mu):
    """The cookbook's threshold: (erf(sigma (p - mu)) + 1) / 2."""
    return (math.erf(sigma * (p - mu)) + 1.0) / 2.0


def mean_threshold(sigma, mu):
    """Mean of threshold(p, sigma, mu) over p uniform in [0,1] (closed form, as core/looks/threshold_map.c)."""

    def k(y):  # integral from y to infinity of erfc
        return math.exp(-y * y) / math.sqrt(math.pi) - y * math.erfc(y)

    if mu < 0.5:
        return 1.0 - mean_threshold(sigma, 1.0 - mu)
    return (k(sigma * (mu - 1.0)) - k(sigma * mu)) / (2.0 * sigma)


@functools.lru_cache(maxsize=None)
def step_position(tone, sigma):
    """The step position whose mean over a uniform pattern is the tone (the builtin mode's mu),
    by bisection: slower than the node's Newton solver, simpler to read."""
    if tone <= 0.0:
        return 1.0 + 40.0 / sigma
    if tone >= 1.0:
        return -40.0 / sigma
    lo, hi = -30.0 / sigma, 1.0 + 30.0 / sigma
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mean_threshold(sigma, mid) > tone:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def soft_step(u, v):
    """The builtin mode as an image: a soft step (sigma 25) whose position follows the tone so
    that a uniform pattern keeps the tone on average. White paper, black ink."""
    g = threshold(u, 25.0, step_position(v, 25.0))
    return (g,)


def banded(u, v):
    """A hatching-like banded map: the tone is cut into 4 bands (levels 1/8, 3/8, 5/8, 7/8), each
    with a sharp step (sigma 80) at its own position, so strokes come in 4 discrete densities and
    shading reads as toon bands of hatching."""
    level = (min(int(v * 4.0), 3) + 0.5) / 4.0
    g = threshold(u, 80.0, step_position(level, 80.0))
    return (g,)


def ink_wash(u, v):
    """A colour map: a softer step (sigma 15) following the tone, the ink going from a cool dark
    blue in the shadows to a warm sepia in the lights, on warm paper."""
    paper = (0.97, 0.94, 0.86)
    shadow = (0.10, 0.13, 0.25)
    light = (0.55, 0.38, 0.22)
    ink = tuple(s + (l - s) * v for s, l in zip(shadow, light))
    g = threshold(u, 15.0, step_position(v, 15.0))
    return tuple(i + (p - i) * g for i, p in zip(ink, paper))


def write_png16(path, pixels, channels):
    """pixels: rows top first, each a list of channel tuples in [0,1]; 16-bit grey or RGB."""
    raw = bytearray()
    for row in pixels:
        raw.append(0)  # filter: none
        for px in row:
            for c in px:
                raw += struct.pack(">H", max(0, min(65535, int(round(c * 65535.0)))))
    colour_type = 0 if channels == 1 else 2

    def chunk(tag, data):
        return (struct.pack(">I", len(data)) + tag + data +
                struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))

    png = b"\x89PNG\r\n\x1a\n"
    png += chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 16, colour_type, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(bytes(raw), 9))
    png += chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def render(fn):
    rows = []
    for y in range(H):
        v = 1.0 - y / (H - 1)  # top row is v = 1
        rows.append([fn(x / (W - 1), v) for x in range(W)])
    return rows


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    for name, fn, ch in (("soft_step", soft_step, 1), ("banded", banded, 1),
                         ("ink_wash", ink_wash, 3)):
        path = os.path.join(out, name + ".png")
        write_png16(path, render(fn), ch)
        print(path)


if __name__ == "__main__":
    main()
