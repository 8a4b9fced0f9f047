#!/usr/bin/env python3
"""Writes data/leaves/*.leaf: the species the three papers show, as outline + veins.

Deterministic (no randomness): run `python3 data/tools/leafgen.py` from the repository root
to regenerate the committed files. Leaves are about one unit long with the base (petiole)
at the origin and the tip towards +y. Outlines are counter-clockwise; every vein starts at
the base or on its parent and ends inside the blade with a margin; veins never cross.

The palmate leaves are star-shaped around a centre on the midvein, so veins from that centre
to the lobe tips are radial and stay inside; secondary veins are clipped where they would
come closer than MARGIN to the outline. The Table 1 leaves are tuned so perimeter^2 / area
matches the outline/interior spacing their point counts imply (DESIGN.md, Table 1):
maple ~150, plane tree ~25, wisteria ~18.
"""
import math
import os

MARGIN = 0.03


def polygon_area(poly):
    a = 0.0
    for i in range(len(poly)):
        x0, y0 = poly[i - 1]
        x1, y1 = poly[i]
        a += x0 * y1 - x1 * y0
    return 0.5 * a


def perimeter(poly):
    return sum(math.dist(poly[i - 1], poly[i]) for i in range(len(poly)))


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


def crosses(a, b, c, d):
    def o(p, q, r):
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    return (o(a, b, c) > 0) != (o(a, b, d) > 0) and (o(c, d, a) > 0) != (o(c, d, b) > 0) and \
        o(a, b, c) != 0 and o(a, b, d) != 0


def outline_dist(poly, p):
    return min(seg_dist(p, poly[i - 1], poly[i]) for i in range(len(poly)))


def polyline(a, b, n):
    return [(a[0] + (b[0] - a[0]) * k / n, a[1] + (b[1] - a[1]) * k / n) for k in range(n + 1)]


def clip(poly, pts, margin=MARGIN):
    """The longest prefix of pts (after the first point) that keeps the margin."""
    out = [pts[0]]
    for p in pts[1:]:
        if not inside(poly, p) or outline_dist(poly, p) < margin:
            break
        out.append(p)
    return out


def rotate_to_base(poly, base):
    """Outline starting at the vertex nearest the base, which is moved exactly onto it."""
    k = min(range(len(poly)), key=lambda i: math.dist(poly[i], base))
    poly = poly[k:] + poly[:k]
    poly[0] = base
    return poly


def star(lobes, sinus, serration=(0, 0.0), notch=0.0, n=2400, center=(0.0, 0.3), smooth=None):
    """Polar outline r(theta) around center. lobes: (angle_deg, tip_radius, half_width_deg, power).
    sinus: the radius between lobes. serration: (teeth per radian, relative depth)."""
    teeth, depth = serration
    poly = []
    for i in range(n):
        th = -math.pi / 2 + 2 * math.pi * i / n
        r = sinus
        for ang, tip, half, pw in lobes:
            d = math.atan2(math.sin(th - math.radians(ang)), math.cos(th - math.radians(ang)))
            w = math.radians(half)
            if abs(d) < w:
                r = max(r, sinus + (tip - sinus) * math.cos(0.5 * math.pi * d / w) ** pw)
        if teeth:
            phase = (th * teeth) % 1.0
            r *= 1.0 - depth * phase  # saw teeth pointing towards the tip of each lobe side
        if notch:
            d = abs(math.atan2(math.sin(th + math.pi / 2), math.cos(th + math.pi / 2)))
            r *= 1.0 - notch * max(0.0, 1.0 - d / 0.5)
        poly.append((center[0] + r * math.cos(th), center[1] + r * math.sin(th)))
    return poly


def blade(length, width, n=1600, base_power=0.6, tip_power=0.9, serration=(0, 0.0), asym=0.0):
    """Pinnate blade along +y from the base (0, 0): half width h(y) on each side."""
    teeth, depth = serration
    half = n // 2
    right, left = [], []
    for i in range(1, half):
        s = i / half
        y = length * s
        h = width * 0.5 * (math.sin(math.pi * s) ** 0.5) * (s ** base_power) * ((1 - s) ** tip_power) * 3.2
        if teeth:
            h *= 1.0 - depth * ((s * teeth) % 1.0)
        right.append((h * (1 + asym), y))
        left.append((-h * (1 - asym), y))
    return [(0.0, 0.0)] + right + [(0.0, length)] + left[::-1]


def branch(poly, start, angle_deg, length, steps=12, bend=0.0):
    """A secondary vein from start, clipped to the blade."""
    pts = [start]
    a = math.radians(angle_deg)
    step = length / steps
    x, y = start
    for _ in range(steps):
        x += step * math.cos(a)
        y += step * math.sin(a)
        a += math.radians(bend) / steps
        pts.append((x, y))
    return clip(poly, pts)


class Leaf:
    def __init__(self, name, poly, base):
        self.name = name
        self.poly = rotate_to_base(poly, base)
        self.base = base
        self.veins = []  # (order, parent, points)

    def vein(self, order, parent, pts):
        pts = self.keep_apart(pts)
        if len(pts) >= 2 and sum(math.dist(pts[i], pts[i + 1]) for i in range(len(pts) - 1)) > 2 * MARGIN:
            self.veins.append((order, parent, pts))
            return len(self.veins) - 1
        return None

    def keep_apart(self, pts):
        """The prefix of pts that neither crosses nor comes close to an existing vein: veins
        are constrained segments of the triangulation, which must not cross."""
        segments = [(v[2][i], v[2][i + 1]) for v in self.veins for i in range(len(v[2]) - 1)]
        out = [pts[0]]
        for k in range(1, len(pts)):
            a, b = pts[k - 1], pts[k]
            bad = False
            for c, d in segments:
                if pts[0] in (c, d):
                    continue
                if crosses(a, b, c, d) or (k >= 2 and seg_dist(b, c, d) < 0.6 * MARGIN):
                    bad = True
                    break
            if bad:
                break
            out.append(b)
        return out

    def write(self, path):
        a = polygon_area(self.poly)
        assert a > 0, self.name
        ratio = perimeter(self.poly) ** 2 / a
        with open(path + ".tmp", "w") as f:
            f.write("# %s, written by data/tools/leafgen.py (perimeter^2/area = %.1f)\n" % (self.name, ratio))
            f.write("name %s\nbase %.9g %.9g\noutline %d\n" % (self.name, self.base[0], self.base[1], len(self.poly)))
            for x, y in self.poly:
                f.write("%.9g %.9g\n" % (x, y))
            for order, parent, pts in self.veins:
                f.write("vein %d %d %d\n" % (order, parent, len(pts)))
                for x, y in pts:
                    f.write("%.9g %.9g\n" % (x, y))
        os.replace(path + ".tmp", path)
        print("%-11s outline %4d points, %2d veins, perimeter^2/area %.1f" % (self.name, len(self.poly), len(self.veins), ratio))


def radial_point(center, angle_deg, r):
    return (center[0] + r * math.cos(math.radians(angle_deg)), center[1] + r * math.sin(math.radians(angle_deg)))


def palmate(name, lobes, sinus, serration, center, secondary, notch=0.0, sub=None):
    """Palmate leaf: midvein base -> centre -> top lobe, primaries from the centre to the other lobes."""
    poly = star(lobes, sinus, serration, notch=notch, center=center)
    # The base: where the radial line straight down meets the outline.
    base = min(poly, key=lambda p: abs(p[0] - center[0]) + (0 if p[1] < center[1] else 10))
    leaf = Leaf(name, poly, base)
    ordered = sorted(lobes, key=lambda l: abs(l[0] - 90))
    top = ordered[0]
    tip = radial_point(center, top[0], top[1] - 2.2 * MARGIN)
    # Base to centre is radial (inside by construction, though close to the notch); beyond
    # the centre the midvein is clipped like every other vein.
    mid = polyline(base, center, 6)[:-1] + clip(leaf.poly, polyline(center, tip, 16), 0.5 * MARGIN)
    root = leaf.vein(1, -1, mid)
    primaries = [(top, root, leaf.veins[root][2])]
    for lobe in ordered[1:]:
        end = radial_point(center, lobe[0], lobe[1] - 2.2 * MARGIN)
        pts = clip(leaf.poly, polyline(center, end, 16), 0.5 * MARGIN)
        k = leaf.vein(2, root, pts)
        if k is not None:
            primaries.append((lobe, k, leaf.veins[k][2]))
    # Secondary veins: pairs along each primary, angled towards the lobe margins.
    for lobe, k, pts in primaries:
        ang = lobe[0]
        count = secondary
        for s in range(1, count + 1):
            at = pts[min(len(pts) - 2, max(4, int(len(pts) * s / (count + 1.5))))]
            for side in (-1, 1):
                leaf.vein(3, k, branch(leaf.poly, at, ang + side * 48, 0.5 * lobe[1], bend=side * -20))
    return leaf


def pinnate(name, length, width, pairs, serration=(0, 0.0), base_power=0.6, tip_power=0.9, asym=0.0, angle=50):
    poly = blade(length, width, base_power=base_power, tip_power=tip_power, serration=serration, asym=asym)
    leaf = Leaf(name, poly, (0.0, 0.0))
    mid = [(0.0, 0.0)] + clip(leaf.poly, polyline((0.0, 0.0), (0.0, length * 0.97), 40)[1:], 0.5 * MARGIN)
    root = leaf.vein(1, -1, mid)
    mid = leaf.veins[root][2]
    for k in range(pairs):
        s = 0.12 + 0.78 * k / max(1, pairs - 1)
        at = mid[min(len(mid) - 2, int(s * (len(mid) - 1)))]
        for side in (-1, 1):
            a = 90 - side * (90 - angle) if side > 0 else 90 + (90 - angle)
            leaf.vein(2, root, branch(leaf.poly, at, a, width * 0.9, steps=14, bend=-side * -25 if side > 0 else 25))
    return leaf


def maple():
    # Japanese maple: 7 deep narrow lobes, doubly serrate; basal lobes small (Fig. 17).
    lobes = [(90, 0.62, 30, 1.6), (90 + 49, 0.57, 28, 1.6), (90 - 49, 0.57, 28, 1.6),
             (90 + 98, 0.44, 26, 1.6), (90 - 98, 0.44, 26, 1.6), (90 + 145, 0.28, 22, 1.6), (90 - 145, 0.28, 22, 1.6)]
    return palmate("maple", lobes, 0.1, (4.4, 0.16), (0.0, 0.36), 3, notch=0.35)


def plane():
    # Plane tree: 5 broad lobes with a few coarse teeth, palmate veins.
    lobes = [(90, 0.52, 48, 1.0), (90 + 55, 0.47, 40, 1.0), (90 - 55, 0.47, 40, 1.0),
             (90 + 118, 0.33, 36, 1.0), (90 - 118, 0.33, 36, 1.0)]
    return palmate("plane", lobes, 0.22, (2.2, 0.12), (0.0, 0.33), 3, notch=0.25)


def hibiscus():
    lobes = [(90, 0.55, 95, 0.8), (90 + 60, 0.42, 60, 1.0), (90 - 60, 0.42, 60, 1.0)]
    return palmate("hibiscus", lobes, 0.33, (3.2, 0.05), (0.0, 0.36), 3, notch=0.2)


def cucumber():
    lobes = [(90, 0.55, 50, 0.8), (90 + 55, 0.5, 45, 0.8), (90 - 55, 0.5, 45, 0.8),
             (90 + 115, 0.42, 40, 0.8), (90 - 115, 0.42, 40, 0.8)]
    return palmate("cucumber", lobes, 0.34, (2.6, 0.07), (0.0, 0.4), 2, notch=0.3)


def watermelon():
    # Palmate with deep pinnately cut lobes: each main lobe carries two pairs of side lobes.
    lobes = [(90, 0.6, 14, 1.4), (90 + 60, 0.52, 13, 1.4), (90 - 60, 0.52, 13, 1.4)]
    for ang, tip in ((90, 0.6), (150, 0.52), (30, 0.52)):
        for off, frac in ((26, 0.55), (-26, 0.55), (44, 0.4), (-44, 0.4)):
            lobes.append((ang + off * 0.7, tip * frac + 0.1, 9, 1.4))
    lobes += [(90 + 128, 0.3, 14, 1.4), (90 - 128, 0.3, 14, 1.4)]
    return palmate("watermelon", lobes, 0.09, (0, 0.0), (0.0, 0.3), 1, notch=0.2)


def wisteria():
    # Wisteria leaflet: elliptic, entire margin, pinnate venation.
    return pinnate("wisteria", 1.0, 0.36, 6, base_power=0.45, tip_power=0.75, angle=52)


def hickory():
    # Shellbark hickory leaflet: long elliptic-lanceolate, finely serrate, slightly oblique base.
    return pinnate("hickory", 1.0, 0.3, 9, serration=(38, 0.06), base_power=0.5, tip_power=1.0, asym=0.08, angle=48)


def grass():
    # Grass blade: long and narrow, parallel veins from the base converging towards the tip.
    length, width = 1.0, 0.09
    n = 800
    right, left = [], []
    for i in range(1, n):
        s = i / n
        h = 0.5 * width * min(1.0, s / 0.06) * (1.0 - s) ** 0.45
        right.append((h, length * s))
        left.append((-h, length * s))
    poly = [(0.0, 0.0)] + right + [(0.0, length)] + left[::-1]
    leaf = Leaf("grass", poly, (0.0, 0.0))
    mid = [(0.0, 0.0)] + clip(leaf.poly, polyline((0.0, 0.0), (0.0, 0.96), 60)[1:], 0.25 * 0.5 * width)
    root = leaf.vein(1, -1, mid)
    for frac in (-0.55, 0.55, -0.27, 0.27):
        pts = [mid[2]]
        for k in range(3, 55):
            y = mid[k][1]
            h = 0.5 * width * min(1.0, y / 0.06) * (1.0 - y) ** 0.45
            pts.append((frac * h, y))
        leaf.vein(2, root, clip(leaf.poly, pts, 0.1 * width))
    return leaf


def ginkgo():
    # Fan-shaped blade with a central notch; dichotomously forking veins from the base.
    n = 1800
    spread = 0.95
    pts = []
    for i in range(n + 1):
        a = math.pi / 2 - spread + 2 * spread * i / n
        r = 0.95 * (1 - 0.05 * math.cos(7 * (a - math.pi / 2))) * (1 - 0.25 * max(0.0, 1 - abs(a - math.pi / 2) / 0.08))
        pts.append((r * math.cos(a), 0.08 + r * math.sin(a)))
    # From the base up the right edge, along the rim from right to left, back down the left edge.
    right = polyline((0.0, 0.0), pts[0], 30)[1:-1]
    left = polyline(pts[-1], (0.0, 0.0), 30)[1:-1]
    poly = [(0.0, 0.0)] + right + pts + left
    leaf = Leaf("ginkgo", poly, (0.0, 0.0))
    origin = (0.0, 0.08)

    def ray(a_deg, r):
        return (origin[0] + r * math.cos(math.radians(a_deg)), origin[1] + r * math.sin(math.radians(a_deg)))

    stem = [(0.0, 0.0), origin]
    first = leaf.vein(1, -1, stem + [ray(90 - 20, 0.2)])
    second = leaf.vein(1, 0, [origin, ray(90 + 20, 0.2)])

    def fork(parent, pts, a, r, depth, order):
        if depth == 0:
            return
        for side in (-1, 1):
            a2 = a + side * 20 / (1.3 ** (3 - depth))
            r2 = min(r + 0.28, 0.82)
            child = clip(leaf.poly, polyline(pts[-1], ray(a2, r2), 6), 0.04)
            k = leaf.vein(order, parent, child)
            if k is not None and len(leaf.veins[k][2]) == 7:
                fork(k, leaf.veins[k][2], a2, r2, depth - 1, order + 1)

    fork(first, leaf.veins[first][2], 90 - 20, 0.2, 3, 2)
    fork(second, leaf.veins[second][2], 90 + 20, 0.2, 3, 2)
    return leaf


def main():
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "leaves")
    for make in (maple, plane, wisteria, hibiscus, ginkgo, grass, hickory, cucumber, watermelon):
        leaf = make()
        leaf.write(os.path.join(out, leaf.name + ".leaf"))


if __name__ == "__main__":
    main()
