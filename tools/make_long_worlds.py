#!/usr/bin/python3
"""Generate the long-horizon benchmark worlds in scenarios/long/.

Writes scenarios/long/maps/NAME.pgm (binary PGM, P5, dark = occupied, row 0 at
the top, 0.1 m per pixel) and scenarios/long/NAME.yaml for every world below.
Everything is deterministic (a private splitmix64 stream per world, no
dependence on Python's `random`): running the script again rewrites the same
bytes. `--check` compares instead of writing and exits 1 on a difference.

Worlds are designed on the robots' lattice (0.5 m cells, lattice points at the
cell centres, as with the default robots.step). A wall cell is drawn as a
0.3 m thick line through the cell centre, joined to the neighbouring wall
cells (a 2 x 2 block of wall cells is drawn solid), so the lattice point of
every non-wall cell is free (0.35 m from the nearest wall, the robot radius is
0.15 m) and every wall cell's point is blocked: the free lattice is exactly
the set of non-wall cells. A corridor of k free cells between two walls is
0.5 (k + 1) - 0.3 m wide (3 cells: 1.7 m).

Stdlib only.
"""

import argparse
import os
import sys
from collections import deque

CELL = 0.5  # lattice step, metres
PX = 5  # pixels per cell (0.1 m per pixel)


class Rng:
    """splitmix64: a small, fully specified stream (identical everywhere)."""

    def __init__(self, seed):
        self.s = seed & 0xFFFFFFFFFFFFFFFF

    def next(self):
        self.s = (self.s + 0x9E3779B97F4A7C15) & 0xFFFFFFFFFFFFFFFF
        z = self.s
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
        return z ^ (z >> 31)

    def below(self, n):
        """Uniform integer in [0, n)."""
        return self.next() % n

    def chance(self, p):
        return self.next() < p * 2.0**64

    def shuffle(self, xs):
        for i in range(len(xs) - 1, 0, -1):
            j = self.below(i + 1)
            xs[i], xs[j] = xs[j], xs[i]


class Grid:
    """Wall cells of a world of nx x ny lattice cells; (i, j) with j upwards."""

    def __init__(self, nx, ny):
        self.nx, self.ny = nx, ny
        self.w = [[False] * nx for _ in range(ny)]

    def wall(self, i, j):
        return 0 <= i < self.nx and 0 <= j < self.ny and self.w[j][i]

    def set(self, i, j, v=True):
        if 0 <= i < self.nx and 0 <= j < self.ny:
            self.w[j][i] = v

    def hline(self, j, i0, i1, v=True):
        for i in range(i0, i1 + 1):
            self.set(i, j, v)

    def vline(self, i, j0, j1, v=True):
        for j in range(j0, j1 + 1):
            self.set(i, j, v)

    def rect(self, i0, j0, i1, j1, v=True):
        for j in range(j0, j1 + 1):
            self.hline(j, i0, i1, v)

    def neighbours(self, i, j):
        for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            a, b = i + di, j + dj
            if 0 <= a < self.nx and 0 <= b < self.ny and not self.w[b][a]:
                yield a, b

    def bfs(self, start):
        """Free cells reachable from start, in BFS order (4-connected)."""
        seen = {start}
        order = []
        q = deque([start])
        while q:
            c = q.popleft()
            order.append(c)
            for n in self.neighbours(*c):
                if n not in seen:
                    seen.add(n)
                    q.append(n)
        return order

    def num_free(self):
        return sum(1 for row in self.w for v in row if not v)


def render(g):
    """The grid as 8-bit grey pixels, row 0 at the top; returns (w, h, bytes)."""
    W, H = g.nx * PX, g.ny * PX
    img = bytearray(b"\xff" * (W * H))

    def fill(x0, x1, y0, y1):  # pixel ranges, y upwards, half-open
        for y in range(max(0, y0), min(H, y1)):
            r = (H - 1 - y) * W
            img[r + max(0, x0):r + min(W, x1)] = b"\x00" * (min(W, x1) - max(0, x0))

    for j in range(g.ny):
        for i in range(g.nx):
            if not g.w[j][i]:
                continue
            x0 = 0 if i == 0 else PX * i + 1
            x1 = W if i == g.nx - 1 else PX * i + 4
            y0 = 0 if j == 0 else PX * j + 1
            y1 = H if j == g.ny - 1 else PX * j + 4
            fill(x0, x1, y0, y1)
            right, up = g.wall(i + 1, j), g.wall(i, j + 1)
            if right:
                fill(PX * i + 4, PX * i + 6, y0, y1)
            if up:
                fill(x0, x1, PX * j + 4, PX * j + 6)
            if right and up and g.wall(i + 1, j + 1):
                fill(PX * i + 4, PX * i + 6, PX * j + 4, PX * j + 6)
    return W, H, bytes(img)


def pgm_bytes(g, name):
    W, H, img = render(g)
    header = ("P5\n# aia long-horizon world %s: 0.1 m per pixel, %g x %g m, "
              "dark = occupied (tools/make_long_worlds.py)\n%d %d\n255\n" %
              (name, g.nx * CELL, g.ny * CELL, W, H))
    return header.encode("ascii") + img


# ---------------------------------------------------------------- builders


def maze(nx, ny, pitch, rng, braid=0.0, order=None):
    """A maze of (nx // pitch) x (ny // pitch) cells: pitch - 1 free lattice
    cells wide corridors, one-cell walls on the grid lines i % pitch ==
    pitch - 1 (the last line is the top / right border). The passages are a
    random spanning tree (randomised DFS) or, with `order`, the path through
    the maze cells in that order; `braid` is the chance that a dead end gets
    one more opening (loops)."""
    g = Grid(nx, ny)
    mx, my = nx // pitch, ny // pitch
    for i in range(nx):
        if i % pitch == pitch - 1:
            g.vline(i, 0, ny - 1)
    for j in range(ny):
        if j % pitch == pitch - 1:
            g.hline(j, 0, nx - 1)
    # Leftover rows / columns beyond the last maze cell stay wall.
    g.rect(mx * pitch, 0, nx - 1, ny - 1)
    g.rect(0, my * pitch, nx - 1, ny - 1)

    def carve(a, b):
        (ax, ay), (bx, by) = a, b
        if ay == by:  # horizontal neighbours: open the wall column between
            x = pitch * min(ax, bx) + pitch - 1
            g.vline(x, pitch * ay, pitch * ay + pitch - 2, False)
        else:
            y = pitch * min(ay, by) + pitch - 1
            g.hline(y, pitch * ax, pitch * ax + pitch - 2, False)

    links = {}

    def link(a, b):
        links.setdefault(a, set()).add(b)
        links.setdefault(b, set()).add(a)
        carve(a, b)

    def adj(c):
        x, y = c
        out = []
        for dx, dy in ((1, 0), (0, 1), (-1, 0), (0, -1)):
            if 0 <= x + dx < mx and 0 <= y + dy < my:
                out.append((x + dx, y + dy))
        return out

    if order is not None:
        for a, b in zip(order, order[1:]):
            link(a, b)
    else:
        seen = {(0, 0)}
        stack = [(0, 0)]
        while stack:
            c = stack[-1]
            nbrs = [n for n in adj(c) if n not in seen]
            if not nbrs:
                stack.pop()
                continue
            n = nbrs[rng.below(len(nbrs))]
            seen.add(n)
            link(c, n)
            stack.append(n)
    if braid > 0.0:
        for y in range(my):
            for x in range(mx):
                c = (x, y)
                if len(links.get(c, ())) == 1 and rng.chance(braid):
                    cand = [n for n in adj(c) if n not in links[c]]
                    if cand:
                        link(c, cand[rng.below(len(cand))])
    return g


def spiral_order(mx, my):
    """Maze cells from (0, 0) spiralling inwards (right, up, left, down)."""
    x0, y0, x1, y1 = 0, 0, mx - 1, my - 1
    out = []
    while x0 <= x1 and y0 <= y1:
        out += [(x, y0) for x in range(x0, x1 + 1)]
        out += [(x1, y) for y in range(y0 + 1, y1 + 1)]
        if y1 > y0:
            out += [(x, y1) for x in range(x1 - 1, x0 - 1, -1)]
        if x1 > x0:
            out += [(x0, y) for y in range(y1 - 1, y0, -1)]
        x0, y0, x1, y1 = x0 + 1, y0 + 1, x1 - 1, y1 - 1
    return out


def serpentine_order(mx, my):
    """Maze cells column by column, up one column and down the next."""
    out = []
    for x in range(mx):
        ys = range(my) if x % 2 == 0 else range(my - 1, -1, -1)
        out += [(x, y) for y in ys]
    return out


def door_h(g, j, i0, i1, rng, width=2):
    """Open a door of `width` cells in the horizontal wall j within i0..i1."""
    a = i0 + rng.below(i1 - i0 - width + 2)
    g.hline(j, a, a + width - 1, False)


def door_v(g, i, j0, j1, rng, width=2):
    a = j0 + rng.below(j1 - j0 - width + 2)
    g.vline(i, a, a + width - 1, False)


def splits(lo, hi, n, rng, jitter=2):
    """n - 1 separator positions dividing lo..hi into n parts, jittered."""
    out = []
    for k in range(1, n):
        p = lo + (hi - lo + 1) * k // n - 1
        p += rng.below(2 * jitter + 1) - jitter
        out.append(p)
    return out


def room_band(g, i0, i1, j0, j1, rooms, door_j, rng):
    """Rooms side by side in the rectangle i0..i1 x j0..j1 (free cells),
    separated by vertical walls, each with a 2-cell door in the horizontal
    wall at door_j (the band's wall facing the corridor)."""
    seps = splits(i0, i1, rooms, rng)
    for s in seps:
        g.vline(s, j0, j1)
    edges = [i0] + [s + 1 for s in seps]
    ends = [s - 1 for s in seps] + [i1]
    for a, b in zip(edges, ends):
        door_h(g, door_j, a, b, rng)


def office20(rng):
    # 20 x 20 m: a corridor across the middle and a second one up the middle
    # of the top half (a T); three rooms below, two per wing above. The
    # robots start in the bottom-left room.
    g = Grid(40, 40)
    g.hline(17, 0, 39)
    g.hline(22, 0, 39)
    room_band(g, 0, 39, 0, 16, 3, 17, rng)
    g.vline(17, 22, 39)
    g.vline(22, 22, 39)
    g.hline(22, 18, 21, False)  # the vertical corridor opens onto the other
    g.hline(30, 0, 17)
    g.hline(30, 22, 39)
    door_v(g, 17, 23, 29, rng)
    door_v(g, 17, 31, 39, rng)
    door_v(g, 22, 23, 29, rng)
    door_v(g, 22, 31, 39, rng)
    return g


def office30(rng):
    # 30 x 20 m: one long corridor (closed at both ends) with five rooms on
    # each side; each room has one door. The robots start in the bottom-left
    # room.
    g = Grid(60, 40)
    g.hline(16, 0, 59)
    g.hline(21, 0, 59)
    room_band(g, 0, 59, 0, 15, 5, 16, rng)
    room_band(g, 0, 59, 22, 39, 5, 21, rng)
    return g


def office40(rng):
    # 40 x 40 m: two long corridors joined only at the right end (a U), rooms
    # on both sides of each. The robots start in the bottom-left room.
    g = Grid(80, 80)
    g.vline(79, 0, 79)  # right border wall
    g.hline(23, 0, 78)  # corridor 1: j 24..27, i 0..78
    g.hline(56, 0, 78)  # corridor 2: j 52..55
    g.hline(28, 0, 74)
    g.hline(51, 0, 74)
    g.hline(39, 0, 74)
    g.vline(74, 28, 51)  # the joining corridor: i 75..78, j 24..55
    room_band(g, 0, 78, 0, 22, 6, 23, rng)
    room_band(g, 0, 73, 29, 38, 6, 28, rng)
    room_band(g, 0, 73, 40, 50, 6, 51, rng)
    room_band(g, 0, 78, 57, 79, 6, 56, rng)
    return g


def ring30(rng):
    # 30 x 30 m: a 2.1 m loop corridor along the border around a 3 x 3 block
    # of rooms; the eight outer rooms open onto the loop, the centre room
    # only through the room above it. The robots start in the bottom-left
    # corner of the loop.
    g = Grid(60, 60)
    lo, hi = 4, 55  # inner block walls
    g.hline(lo, lo, hi)
    g.hline(hi, lo, hi)
    g.vline(lo, lo, hi)
    g.vline(hi, lo, hi)
    cuts = [lo, 21, 38, hi]
    for c in cuts[1:-1]:
        g.vline(c, lo, hi)
        g.hline(c, lo, hi)
    for a in range(3):
        for b in range(3):
            i0, i1 = cuts[a] + 1, cuts[a + 1] - 1
            j0, j1 = cuts[b] + 1, cuts[b + 1] - 1
            if (a, b) == (1, 1):
                door_h(g, cuts[2], i0, i1, rng)  # centre room: from above
                continue
            # One door onto the loop, on the side away from the start corner
            # where the room has a choice.
            if b == 2:
                door_h(g, hi, i0, i1, rng)
            elif a == 2:
                door_v(g, hi, j0, j1, rng)
            elif b == 0:
                door_h(g, lo, i0, i1, rng)
            else:
                door_v(g, lo, j0, j1, rng)
    return g


def warehouse40(rng):
    # 40 x 30 m: nine rows of 0.8 m deep shelves (solid), 2.2 m aisles, a
    # cross-aisle at both ends and a middle cross-aisle through every other
    # row only. The robots start at the dock in the bottom-left corner.
    g = Grid(80, 60)
    for k in range(9):
        j = 6 + 6 * k
        if k % 2 == 0:
            g.rect(6, j, 36, j + 1)
            g.rect(41, j, 73, j + 1)
        else:
            g.rect(6, j, 73, j + 1)
    return g


def campus40(rng):
    # 40 x 40 m: 8 x 8 rooms of 4.5 m, connected by 1 m doors along a random
    # spanning tree plus a few extra doors (a maze of rooms).
    g = Grid(80, 80)
    pitch = 10
    for k in range(1, 8):
        g.vline(pitch * k - 1, 0, 79)
        g.hline(pitch * k - 1, 0, 79)
    g.vline(79, 0, 79)
    g.hline(79, 0, 79)
    m = 8
    seen = {(0, 0)}
    stack = [(0, 0)]
    opened = set()

    def open_door(a, b):
        opened.add((min(a, b), max(a, b)))
        (ax, ay), (bx, by) = a, b
        if ay == by:
            x = pitch * min(ax, bx) + pitch - 1
            door_v(g, x, pitch * ay, pitch * ay + pitch - 2, rng)
        else:
            y = pitch * min(ay, by) + pitch - 1
            door_h(g, y, pitch * ax, pitch * ax + pitch - 2, rng)

    def adj(c):
        x, y = c
        return [(x + dx, y + dy) for dx, dy in ((1, 0), (0, 1), (-1, 0), (0, -1))
                if 0 <= x + dx < m and 0 <= y + dy < m]

    while stack:
        c = stack[-1]
        nbrs = [n for n in adj(c) if n not in seen]
        if not nbrs:
            stack.pop()
            continue
        n = nbrs[rng.below(len(nbrs))]
        seen.add(n)
        open_door(c, n)
        stack.append(n)
    extra = 0
    while extra < 8:
        a = (rng.below(m), rng.below(m))
        nb = adj(a)
        b = nb[rng.below(len(nb))]
        if (min(a, b), max(a, b)) in opened:
            continue
        open_door(a, b)
        extra += 1
    return g


# ---------------------------------------------------------------- the worlds

WORLDS = [
    # name, builder, robots, targets, seed, max_steps, title, description
    ("maze20", lambda r: maze(40, 40, 4, r), 4, 6, 1, 1000,
     "20 x 20 m perfect maze",
     "10 x 10 maze cells, 1.7 m corridors, a single path between any two "
     "places: long detours around walls that the sensor cannot see through."),
    ("maze30", lambda r: maze(60, 60, 4, r), 6, 8, 1, 1500,
     "30 x 30 m perfect maze",
     "15 x 15 maze cells, 1.7 m corridors, no loops: targets deep in dead "
     "ends."),
    ("maze30_loops", lambda r: maze(60, 60, 4, r, braid=0.5), 8, 10, 2, 1500,
     "30 x 30 m braided maze",
     "15 x 15 maze cells, 1.7 m corridors; half the dead ends opened into "
     "loops, so there are several routes of different lengths."),
    ("maze40_wide", lambda r: maze(80, 80, 5, r), 10, 10, 1, 2000,
     "40 x 40 m perfect maze with wide corridors",
     "16 x 16 maze cells, 2.2 m corridors, ten robots: the longest routes."),
    ("spiral20", lambda r: maze(40, 40, 4, r, order=spiral_order(10, 10)), 3,
     5, 1, 1500,
     "20 x 20 m square spiral",
     "One 1.7 m corridor spiralling from the start corner to the centre "
     "(about 200 m long): every target lies on a single long route."),
    ("switchback30", lambda r: maze(60, 28, 4, r,
                                    order=serpentine_order(15, 7)), 4, 6, 2,
     1500,
     "30 x 14 m switchback corridor",
     "One 1.7 m corridor folding up and down the world 15 times (about "
     "200 m): neighbours across a wall are far apart along the route."),
    ("office20", office20, 3, 5, 1, 1000,
     "20 x 20 m office, T-shaped corridor",
     "Three rooms below a corridor, four rooms on the two sides of a second "
     "corridor above it; one door per room."),
    ("office30", office30, 6, 8, 1, 1000,
     "30 x 20 m office, one long corridor",
     "Ten rooms, five each side of a corridor closed at both ends; one door "
     "per room, so every room is a dead end."),
    ("office40", office40, 10, 10, 1, 1500,
     "40 x 40 m office floor, U-shaped corridors",
     "Two long corridors joined only at the far end, 24 rooms with one door "
     "each: the top half is reached by going all the way round."),
    ("ring30", ring30, 6, 8, 1, 1000,
     "30 x 30 m loop corridor",
     "A 2.1 m corridor around a 3 x 3 block of rooms; two ways round the "
     "loop, doors on the far sides, and a centre room reached through "
     "another room."),
    ("warehouse40", warehouse40, 8, 10, 1, 1000,
     "40 x 30 m warehouse",
     "Nine 0.8 m shelf rows (sensing is blocked by shelves), 2.2 m aisles, "
     "cross-aisles at both ends and through every other row in the middle."),
    ("campus40", campus40, 8, 10, 1, 2000,
     "40 x 40 m maze of rooms",
     "8 x 8 rooms of 4.5 m joined by 1 m doors along a random spanning tree "
     "plus eight extra doors: rooms must be entered to see their targets."),
]


def fmt(v):
    s = ("%.2f" % v).rstrip("0")
    return s + "0" if s.endswith(".") else s


def scenario_text(header, scenario, name, g, robots, targets, seed,
                  max_steps, starts):
    """The scenario file: the comment lines `header`, then the world of map
    maps/NAME.pgm with the robots at the lattice cells `starts`."""
    lines = list(header) + [
        "name: %s" % scenario,
        "seed: %d" % seed,
        "workspace:",
        "  size: [%s, %s]" % (fmt(g.nx * CELL), fmt(g.ny * CELL)),
        "  obstacles:",
        "    map: maps/%s.pgm" % name,
        "robots:",
        "  count: %d" % robots,
        "  start:",
    ]
    for (i, j) in starts:
        lines.append("    - [%s, %s]" % (fmt((i + 0.5) * CELL),
                                        fmt((j + 0.5) * CELL)))
    lines += [
        "targets:",
        "  count: %d" % targets,
        "mission: {eps: 0.1, max_steps: %d}" % max_steps,
        "policy: {name: greedy}",
    ]
    return "\n".join(lines) + "\n"


def yaml_text(name, g, robots, targets, seed, max_steps, title, desc, starts):
    lines = ["# Long-horizon benchmark world '%s': %s." % (name, title)]
    words = desc.split()
    cur = "#"
    for w in words:
        if len(cur) + 1 + len(w) > 78:
            lines.append(cur)
            cur = "#"
        cur += " " + w
    lines.append(cur)
    lines += [
        "# Map: maps/%s.pgm (%d x %d px, 0.1 m per pixel, dark = occupied)," %
        (name, g.nx * PX, g.ny * PX),
        "# %d robots starting together in the bottom-left corner, %d random "
        "static targets." % (robots, targets),
        "# Generated by tools/make_long_worlds.py (do not edit by hand).",
    ]
    return scenario_text(lines, "long_" + name, name, g, robots, targets,
                         seed, max_steps, starts)


def build_all(root):
    """{path: bytes} of every file to write."""
    out = {}
    for k, (name, build, robots, targets, seed, max_steps, title,
            desc) in enumerate(WORLDS):
        rng = Rng(0xA1A0000 + k)
        g = build(rng)
        assert not g.wall(0, 0), name
        reach = g.bfs((0, 0))
        if len(reach) != g.num_free():
            raise SystemExit("%s: %d free cells, %d reachable from the start"
                             % (name, g.num_free(), len(reach)))
        starts = reach[:robots]
        out[os.path.join(root, "maps", name + ".pgm")] = pgm_bytes(g, name)
        out[os.path.join(root, name + ".yaml")] = yaml_text(
            name, g, robots, targets, seed, max_steps, title, desc,
            starts).encode("ascii")
    return out


def write_or_check(description, default_root, build):
    """The world makers' command line: build(root) gives {path: bytes};
    write them under --root (default `default_root`), or with --check
    compare them with the files there (exit 1 on a difference)."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--root", default=default_root,
                    help="output folder (default: %s)" % os.path.relpath(
                        default_root, os.path.join(
                            os.path.dirname(os.path.abspath(__file__)), "..")))
    ap.add_argument("--check", action="store_true",
                    help="compare with the files on disk instead of writing; "
                    "exit 1 on a difference")
    args = ap.parse_args()
    root = os.path.normpath(args.root)
    files = build(root)
    bad = 0
    for path in sorted(files):
        data = files[path]
        if args.check:
            try:
                with open(path, "rb") as f:
                    same = f.read() == data
            except OSError:
                same = False
            if not same:
                print("differs: " + path)
                bad += 1
            continue
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as f:
            f.write(data)
    if args.check:
        print("%d files, %d differ" % (len(files), bad))
        return 1 if bad else 0
    print("wrote %d files under %s" % (len(files), root))
    return 0


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    return write_or_check(__doc__.split("\n\n")[0],
                          os.path.join(here, "..", "scenarios", "long"),
                          build_all)

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from tool_io import run  # one error line for bad paths, not a traceback
    run(main)
