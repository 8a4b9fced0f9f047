#!/usr/bin/env python3
"""Writes the maple of `sere season` (seed 002, Tang, Wu & Fan 2013) in one 512 x 512 pixel frame:

  data/seasons/maple.keys        key points on the leaf's edge, petiole first (Sec. 3, Fig. 1a)
  data/masks/maple.pgm           mask map like Fig. 3b: dark at the lobe corners and near the
                                 petiole (light particles, more deformation), bright elsewhere
  data/masks/maple_veins.pgm     mask map like Fig. 5: the primary veins painted white, the blade
                                 between them dark, so the two sides of each vein curl
  data/masks/uniform.pgm         one gray everywhere: equal masses, the baseline
  data/masks/maple_silhouette.png  the leaf as a black silhouette on white, for --silhouette

Run from the repository root: python3 data/masks/maskgen.py. Pure Python (zlib for the PNG).
Mask pixels inside the leaf and within MARGIN pixels of its edge carry the painted gray; the rest
of the picture is black. The margin keeps the bilinear lookup at outline vertices inside the
painted field.
"""
import math
import os
import struct
import zlib

SIZE = 512
SCALE = 330.0                 # pixels per leaf unit
BASE = (256.0, 390.0)         # the petiole in pixels
MARGIN = 12.0                 # painted pixels outside the leaf
CENTER = (0.0, 0.4)           # lobe centre in leaf units (petiole at the origin, y up)
SINUS = 0.19
# (angle in degrees, tip radius, half width in degrees, sharpness): a Norway-maple-like blade
# with five pointed lobes, the lower pair smaller.
LOBES = [(90, 0.64, 36, 1.3), (90 + 58, 0.6, 34, 1.3), (90 - 58, 0.6, 34, 1.3),
         (90 + 122, 0.4, 28, 1.3), (90 - 122, 0.4, 28, 1.3)]
NOTCH = 0.3                   # depth of the petiole sinus, as a fraction of the radius
KEY_POINTS = 60


def radius(th):
    r = SINUS
    for ang, tip, half, pw in LOBES:
        d = math.atan2(math.sin(th - math.radians(ang)), math.cos(th - math.radians(ang)))
        w = math.radians(half)
        if abs(d) < w:
            r = max(r, SINUS + (tip - SINUS) * (1.0 - abs(d) / w) ** pw)
    d = abs(math.atan2(math.sin(th + math.pi / 2), math.cos(th + math.pi / 2)))
    return r * (1.0 - NOTCH * max(0.0, 1.0 - d / 0.4) ** 2)


def leaf_point(th):
    r = radius(th)
    return (CENTER[0] + r * math.cos(th), CENTER[1] + r * math.sin(th))


def to_pixels(p):
    return (BASE[0] + SCALE * p[0], BASE[1] - SCALE * p[1])


def outline(n=4000):
    """Counter-clockwise in leaf units from the petiole (straight below the centre)."""
    pts = [leaf_point(-math.pi / 2 + 2 * math.pi * i / n) for i in range(n)]
    # Move the lobe centre so the petiole sinus lands exactly on the origin.
    shift = pts[0]
    return [(x - shift[0], y - shift[1]) for x, y in pts]


def key_points(poly):
    """The petiole, every lobe tip and every sinus, and points spread evenly by arc length
    between them: what a user clicking along the edge would pick."""
    n = len(poly)
    angles = sorted(a for a, _, _, _ in LOBES)
    marks = [a for a in angles] + [0.5 * (angles[k] + angles[k + 1]) for k in range(len(angles) - 1)]
    # Outline index i sits at angle -90 + 360 i / n degrees.
    extremes = sorted({0} | {round((a + 90.0) % 360.0 / 360.0 * n) % n for a in marks})
    seg = [math.dist(poly[i], poly[(i + 1) % n]) for i in range(n)]
    step = sum(seg) / KEY_POINTS
    keys = []
    for e, start in enumerate(extremes):
        end = extremes[e + 1] if e + 1 < len(extremes) else n
        length = sum(seg[start:end])
        count = max(1, round(length / step))
        acc, k = 0.0, start
        for j in range(count):
            target = length * j / count
            while k < end - 1 and acc + seg[k] < target:
                acc += seg[k]
                k += 1
            keys.append(poly[k])
    return keys


def inside(poly, p):
    x, y = p
    c = False
    j = len(poly) - 1
    for i in range(len(poly)):
        xi, yi = poly[i]
        xj, yj = poly[j]
        if (yi > y) != (yj > y) and x < xj + (y - yj) * (xi - xj) / (yi - yj):
            c = not c
        j = i
    return c


def seg_dist(p, a, b):
    ex, ey = b[0] - a[0], b[1] - a[1]
    l2 = ex * ex + ey * ey
    t = 0.0 if l2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / l2))
    return math.hypot(a[0] + t * ex - p[0], a[1] + t * ey - p[1])


def region(poly_px):
    """Per pixel: 2 inside the leaf, 1 within MARGIN of it, 0 outside (pixel centres)."""
    coarse = poly_px[::16]
    rows = []
    for j in range(SIZE):
        y = j + 0.5
        # Scanline crossings of the outline.
        xs = []
        for i in range(len(poly_px)):
            (x0, y0), (x1, y1) = poly_px[i - 1], poly_px[i]
            if (y0 > y) != (y1 > y):
                xs.append(x0 + (y - y0) * (x1 - x0) / (y1 - y0))
        xs.sort()
        row = bytearray(SIZE)
        for a, b in zip(xs[0::2], xs[1::2]):
            for i in range(max(0, int(math.floor(a - 0.5)) + 1), min(SIZE, int(math.ceil(b - 0.5)))):
                row[i] = 2
        for i in range(SIZE):
            if row[i] == 0 and xs and xs[0] - MARGIN - 1 <= i + 0.5 <= xs[-1] + MARGIN + 1:
                p = (i + 0.5, y)
                if min(seg_dist(p, coarse[k - 1], coarse[k]) for k in range(len(coarse))) <= MARGIN:
                    row[i] = 1
        rows.append(row)
    # Rows above and below the leaf within the margin.
    ys = [p[1] for p in poly_px]
    for j in range(max(0, int(min(ys) - MARGIN - 1)), min(SIZE, int(max(ys) + MARGIN + 1))):
        for i in range(SIZE):
            if rows[j][i] == 0:
                p = (i + 0.5, j + 0.5)
                if abs(p[0] - 256) < 260 and min(seg_dist(p, coarse[k - 1], coarse[k]) for k in range(0, len(coarse), 1)) <= MARGIN:
                    rows[j][i] = 1
    return rows


def write_pgm(path, gray, comment):
    with open(path + ".tmp", "wb") as f:
        f.write(b"P5\n")
        for line in comment:
            f.write(("# " + line + "\n").encode())
        f.write(b"%d %d\n255\n" % (SIZE, SIZE))
        for row in gray:
            f.write(bytes(row))
    os.replace(path + ".tmp", path)


def write_png(path, gray):
    raw = b"".join(b"\x00" + bytes(row) for row in gray)

    def chunk(tag, data):
        c = struct.pack(">I", len(data)) + tag + data
        return c + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", SIZE, SIZE, 8, 0, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path + ".tmp", "wb") as f:
        f.write(png)
    os.replace(path + ".tmp", path)


def painted(rows, field):
    out = []
    for j in range(SIZE):
        row = bytearray(SIZE)
        for i in range(SIZE):
            if rows[j][i]:
                x = (i + 0.5 - BASE[0]) / SCALE
                y = (BASE[1] - (j + 0.5)) / SCALE
                row[i] = max(0, min(255, int(round(field(x, y)))))
        out.append(row)
    return out


def main():
    poly = outline()
    poly_px = [to_pixels(p) for p in poly]
    keys = key_points(poly)
    with open("data/seasons/maple.keys.tmp", "w") as f:
        f.write("# Key points on the edge of a maple leaf (seed 002, Sec. 3): the points a user would\n")
        f.write("# click along the edge of the leaf's scanned image. Written by data/masks/maskgen.py.\n")
        f.write("# 'image W H' names the pixel frame (shared with the mask maps in data/masks); then one\n")
        f.write("# point per line, x to the right and y down in pixels, in order around the leaf. The\n")
        f.write("# first point is the petiole, where the leaf is attached.\n")
        f.write("image %d %d\n" % (SIZE, SIZE))
        for p in keys:
            x, y = to_pixels(p)
            f.write("%.2f %.2f\n" % (x, y))
    os.replace("data/seasons/maple.keys.tmp", "data/seasons/maple.keys")

    rows = region(poly_px)
    c = (0.0, CENTER[1] - leaf_point(-math.pi / 2)[1])
    tips = [(c[0] + tip * math.cos(math.radians(a)), c[1] + tip * math.sin(math.radians(a))) for a, tip, _, _ in LOBES]

    def corners(x, y):
        dark = 0.0
        for tx, ty in tips:
            dark = max(dark, math.exp(-((x - tx) ** 2 + (y - ty) ** 2) / (2 * 0.085 ** 2)))
        dark = max(dark, math.exp(-(x * x + y * y) / (2 * 0.09 ** 2)))
        return 235.0 - 215.0 * dark

    def veins(x, y):
        d = min(seg_dist((x, y), (0.0, 0.0), c), min(seg_dist((x, y), c, t) for t in tips))
        return 40.0 + 210.0 * math.exp(-d * d / (2 * 0.022 ** 2))

    write_pgm("data/masks/maple.pgm", painted(rows, corners),
              ["sere mask map like Fig. 3b of seed 002: dark at the lobe corners and the petiole",
               "written by data/masks/maskgen.py; pixel frame of data/seasons/maple.keys"])
    write_pgm("data/masks/maple_veins.pgm", painted(rows, veins),
              ["sere mask map like Fig. 5 of seed 002: primary veins white, blade dark",
               "written by data/masks/maskgen.py; pixel frame of data/seasons/maple.keys"])
    write_pgm("data/masks/uniform.pgm", [bytearray([200] * SIZE) for _ in range(SIZE)],
              ["sere mask map: one gray everywhere (equal masses)", "written by data/masks/maskgen.py"])
    write_png("data/masks/maple_silhouette.png",
              [bytearray(0 if rows[j][i] == 2 else 255 for i in range(SIZE)) for j in range(SIZE)])
    print("maple: %d key points, outline %d points" % (len(keys), len(poly)))


if __name__ == "__main__":
    main()
