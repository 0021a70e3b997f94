#include "aia/world/generator.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "aia/core/check.h"
#include "aia/core/error.h"
#include "aia/core/rng.h"
#include "aia/world/world.h"

namespace aia {
namespace {

const char kKey[] = "workspace.obstacles.generator";

// The layout on the lattice's cells, one per lattice point (cell (ix, iy) is
// the square of side step around point (ix, iy)): rock fills a cell, a thin
// wall stands on the east or north edge of one.
struct Layout {
  Layout(int nx_, int ny_)
      : nx(nx_), ny(ny_), rock(Size(), 0), east(Size(), 0), north(Size(), 0) {}

  std::size_t Size() const { return static_cast<std::size_t>(nx) * ny; }
  std::size_t At(int ix, int iy) const {
    return static_cast<std::size_t>(iy) * nx + ix;
  }
  // A wall between cells (ix, iy) and (ix + 1, iy).
  void WallEast(int ix, int iy) { east[At(ix, iy)] = 1; }
  // A wall between cells (ix, iy) and (ix, iy + 1).
  void WallNorth(int ix, int iy) { north[At(ix, iy)] = 1; }

  int nx, ny;
  std::vector<std::uint8_t> rock, east, north;
};

// Uniform integer in [lo, hi]; lo <= hi.
int UniformIn(Rng& rng, int lo, int hi) {
  AIA_CHECK(lo <= hi);
  return lo + static_cast<int>(rng.UniformInt(static_cast<std::uint64_t>(
                  static_cast<long long>(hi) - lo + 1)));
}

// ---------------------------------------------------------------- maze ---

// Maze cells of `corridor` steps (stretched to fill the lattice), joined by
// a spanning tree drawn by a randomized depth-first search (long winding
// passages), then a share `loops` of the remaining walls opened.
void Maze(const GeneratorConfig& g, double step, Rng& rng, Layout* l) {
  const int p = StepsIn(g.corridor, step);
  AIA_CHECK(p >= 1);
  const int mx = std::max(1, l->nx / p), my = std::max(1, l->ny / p);
  // Lattice cells of maze column a: [colx[a], colx[a + 1]).
  std::vector<int> colx(mx + 1), rowy(my + 1);
  for (int a = 0; a <= mx; ++a)
    colx[a] = static_cast<int>(static_cast<long long>(a) * l->nx / mx);
  for (int b = 0; b <= my; ++b)
    rowy[b] = static_cast<int>(static_cast<long long>(b) * l->ny / my);
  const auto at = [mx](int a, int b) {
    return static_cast<std::size_t>(b) * mx + a;
  };
  const std::size_t n = static_cast<std::size_t>(mx) * my;
  // open_e[c]: the wall east of maze cell c is open; open_n: north.
  std::vector<std::uint8_t> open_e(n, 0), open_n(n, 0), seen(n, 0);
  std::vector<std::size_t> stack;
  const std::size_t start = rng.UniformInt(n);
  seen[start] = 1;
  stack.push_back(start);
  while (!stack.empty()) {
    const std::size_t c = stack.back();
    const int a = static_cast<int>(c % mx), b = static_cast<int>(c / mx);
    // Unvisited neighbours: 0 east, 1 west, 2 north, 3 south.
    int options[4], count = 0;
    if (a + 1 < mx && !seen[at(a + 1, b)]) options[count++] = 0;
    if (a > 0 && !seen[at(a - 1, b)]) options[count++] = 1;
    if (b + 1 < my && !seen[at(a, b + 1)]) options[count++] = 2;
    if (b > 0 && !seen[at(a, b - 1)]) options[count++] = 3;
    if (count == 0) {
      stack.pop_back();
      continue;
    }
    std::size_t next = 0;
    switch (options[rng.UniformInt(count)]) {
      case 0:
        open_e[c] = 1;
        next = at(a + 1, b);
        break;
      case 1:
        next = at(a - 1, b);
        open_e[next] = 1;
        break;
      case 2:
        open_n[c] = 1;
        next = at(a, b + 1);
        break;
      default:
        next = at(a, b - 1);
        open_n[next] = 1;
        break;
    }
    seen[next] = 1;
    stack.push_back(next);
  }
  for (int b = 0; b < my; ++b) {
    for (int a = 0; a < mx; ++a) {
      const std::size_t c = at(a, b);
      if (a + 1 < mx && !open_e[c] && rng.Bernoulli(g.loops)) open_e[c] = 1;
      if (b + 1 < my && !open_n[c] && rng.Bernoulli(g.loops)) open_n[c] = 1;
    }
  }
  for (int b = 0; b < my; ++b) {
    for (int a = 0; a < mx; ++a) {
      const std::size_t c = at(a, b);
      if (a + 1 < mx && !open_e[c])
        for (int iy = rowy[b]; iy < rowy[b + 1]; ++iy)
          l->WallEast(colx[a + 1] - 1, iy);
      if (b + 1 < my && !open_n[c])
        for (int ix = colx[a]; ix < colx[a + 1]; ++ix)
          l->WallNorth(ix, rowy[b + 1] - 1);
    }
  }
}

// --------------------------------------------------------------- rooms ---

// A gap [lo, hi) in a wall on the line x = line (vertical) or y = line.
struct Door {
  bool vertical;
  int line, lo, hi;
};

// A part of the office still to split: cells [x0, x1) x [y0, y1) and the
// doors on its sides.
struct Region {
  int x0, y0, x1, y1;
  std::vector<Door> doors;
};

// Binary space partition: a part with a side longer than room_size's max is
// split across that side at a uniform position leaving at least min on both
// sides (and not through a door on its sides), with one door in the new
// wall; each split joins two connected parts, so the rooms are connected
// (the doors form a spanning tree of the rooms).
void Rooms(const GeneratorConfig& g, double step, Rng& rng, Layout* l) {
  const GeneratorConfig::RoomSteps rooms = g.RoomStepsAt(step);
  const int m = rooms.min;
  const int d = StepsIn(g.door, step);
  AIA_CHECK(d >= 1);
  std::vector<Region> todo;
  todo.push_back({0, 0, l->nx, l->ny, {}});
  std::vector<int> positions;
  while (!todo.empty()) {
    Region r = std::move(todo.back());
    todo.pop_back();
    const int lx = r.x1 - r.x0, ly = r.y1 - r.y0;
    const bool can_x = rooms.Splits(lx);  // split across x
    const bool can_y = rooms.Splits(ly);
    bool axes[2];  // true: a vertical line (split across x)
    int num_axes = 0;
    if (can_x && can_y) {
      const bool x_first = lx > ly || (lx == ly && rng.Bernoulli(0.5));
      axes[0] = x_first;
      axes[1] = !x_first;
      num_axes = 2;
    } else if (can_x || can_y) {
      axes[0] = can_x;
      num_axes = 1;
    }
    for (int k = 0; k < num_axes; ++k) {
      const bool vertical = axes[k];
      const int lo = (vertical ? r.x0 : r.y0) + m;
      const int hi = (vertical ? r.x1 : r.y1) - m;
      positions.clear();
      for (int at = lo; at <= hi; ++at) {
        bool through_door = false;
        for (const Door& door : r.doors)
          if (door.vertical != vertical && door.lo < at && at < door.hi)
            through_door = true;
        if (!through_door) positions.push_back(at);
      }
      if (positions.empty()) continue;
      const int at = positions[rng.UniformInt(positions.size())];
      const int span0 = vertical ? r.y0 : r.x0, span1 = vertical ? r.y1 : r.x1;
      const int width = std::min(d, span1 - span0);
      const int gap = UniformIn(rng, span0, span1 - width);
      const Door door{vertical, at, gap, gap + width};
      for (int i = span0; i < span1; ++i) {
        if (i >= door.lo && i < door.hi) continue;
        if (vertical) {
          l->WallEast(at - 1, i);
        } else {
          l->WallNorth(i, at - 1);
        }
      }
      Region a{r.x0, r.y0, vertical ? at : r.x1, vertical ? r.y1 : at, {door}};
      Region b{vertical ? at : r.x0, vertical ? r.y0 : at, r.x1, r.y1, {door}};
      for (const Door& old : r.doors) {
        // A door on the sides along the new line goes to the part whose
        // extent holds it; one on the other sides to the part on that side.
        if (old.vertical == vertical) {
          (old.line == (vertical ? r.x0 : r.y0) ? a : b).doors.push_back(old);
        } else {
          (old.hi <= at ? a : b).doors.push_back(old);
        }
      }
      todo.push_back(std::move(b));
      todo.push_back(std::move(a));
      break;
    }
  }
}

// ----------------------------------------------------------- corridors ---

// Local coordinates (u along the corridors, v across) over the layout,
// possibly transposed.
struct Frame {
  Layout* l;
  bool swap;
  int Lu() const { return swap ? l->ny : l->nx; }
  int Lv() const { return swap ? l->nx : l->ny; }
  // A wall between local cells (u, v) and (u + 1, v).
  void WallU(int u, int v) {
    if (swap) {
      l->WallNorth(v, u);
    } else {
      l->WallEast(u, v);
    }
  }
  // A wall between local cells (u, v) and (u, v + 1).
  void WallV(int u, int v) {
    if (swap) {
      l->WallEast(v, u);
    } else {
      l->WallNorth(u, v);
    }
  }
};

// A strip across the corridors (v0 <= v < v1): a corridor, or a band of
// rooms whose doors open onto the line door_line (its corridor side).
struct Strip {
  int v0, v1;
  bool corridor;
  int door_line;  // bands: the line of their corridor side
};

// The depths of `bands` bands of rooms, each drawn in [m, big], then moved
// a step at a time until they sum to `avail` (every band at big: deeper
// rooms).
std::vector<int> BandDepths(int bands, int avail, int m, int big, Rng& rng) {
  std::vector<int> depth(bands);
  int sum = 0;
  for (int& x : depth) sum += (x = UniformIn(rng, m, big));
  std::vector<int> pick;
  while (sum != avail) {
    pick.clear();
    for (int i = 0; i < bands; ++i)
      if (sum > avail ? depth[i] > m : depth[i] < big) pick.push_back(i);
    if (pick.empty())  // every band at max: deeper rooms
      for (int i = 0; i < bands; ++i) pick.push_back(i);
    const int i = pick[rng.UniformInt(pick.size())];
    const int by = sum > avail ? -1 : 1;
    depth[i] += by;
    sum += by;
  }
  return depth;
}

// Across the width lv: units of a corridor of c steps between two bands of
// rooms, or, where lv holds no two bands, one corridor on a side of one
// band.
std::vector<Strip> Strips(int lv, int c, int m, int big, Rng& rng) {
  int units = std::max(1, static_cast<int>(std::lround(static_cast<double>(lv) /
                                                       (c + m + big))));
  while (units > 1 && lv < units * (c + 2 * m)) --units;
  const bool two_sided = lv >= c + 2 * m;
  const std::vector<int> depth =
      BandDepths(two_sided ? 2 * units : 1, lv - units * c, m, big, rng);
  std::vector<Strip> strips;
  int v = 0;
  if (two_sided) {
    for (int k = 0; k < units; ++k) {
      strips.push_back({v, v + depth[2 * k], false, v + depth[2 * k]});
      v += depth[2 * k];
      strips.push_back({v, v + c, true, 0});
      v += c;
      strips.push_back({v, v + depth[2 * k + 1], false, v});
      v += depth[2 * k + 1];
    }
  } else if (rng.Bernoulli(0.5)) {  // the corridor along v = 0
    strips.push_back({0, c, true, 0});
    strips.push_back({c, lv, false, c});
  } else {
    strips.push_back({0, lv - c, false, lv - c});
    strips.push_back({lv - c, lv, true, 0});
  }
  return strips;
}

// Along the length lu: the cross corridors and the stretches of rooms
// between them.
struct CrossCorridors {
  std::vector<std::uint8_t> in_cross;     // per u
  std::vector<std::pair<int, int>> gaps;  // room stretches [u0, u1)
};

// Cross corridors [p, p + c), one per 25 m, each in its own equal share of
// the length with at least a room's width beside it.
CrossCorridors Cross(int lu, int c, int m, double step, Rng& rng) {
  const int wanted = static_cast<int>(std::lround(lu * step / 25.0));
  const int cross = std::max(1, std::min(wanted, lu / (c + m)));
  CrossCorridors out;
  out.in_cross.assign(lu, 0);
  int u = 0;
  for (int k = 0; k < cross; ++k) {
    const int s0 = static_cast<int>(static_cast<long long>(k) * lu / cross);
    const int s1 = static_cast<int>(static_cast<long long>(k + 1) * lu / cross);
    const int lo = s0 + m, hi = s1 - c - m;
    const int p = hi >= lo ? UniformIn(rng, lo, hi) : s0;
    if (p > u) out.gaps.push_back({u, p});
    for (int i = p; i < p + c; ++i) out.in_cross[i] = 1;
    u = p + c;
  }
  if (u < lu) out.gaps.push_back({u, lu});
  return out;
}

// One band's walls: rooms of uniform width in [m, big] along each stretch
// (the last taking the rest), each with a door of d steps onto its
// corridor; the band's walls along u, toward its corridor (but the doors)
// and back to back with the next band; the cross corridors' sides through
// it.
void BandWalls(const Strip& s, const CrossCorridors& x, int m, int big, int d,
               Rng& rng, Frame* f) {
  const int lu = f->Lu(), lv = f->Lv();
  std::vector<std::uint8_t> door(lu, 0);
  for (const auto& [g0, g1] : x.gaps) {
    int r0 = g0;
    while (r0 < g1) {
      int r1 = g1;
      const int widest = std::min(big, g1 - r0 - m);
      if (g1 - r0 > big && widest >= m) r1 = r0 + UniformIn(rng, m, widest);
      const int width = std::min(d, r1 - r0);
      const int a = UniformIn(rng, r0, r1 - width);
      for (int i = a; i < a + width; ++i) door[i] = 1;
      if (r1 < g1)
        for (int vv = s.v0; vv < s.v1; ++vv) f->WallU(r1 - 1, vv);
      r0 = r1;
    }
  }
  for (int i = 0; i < lu; ++i) {
    if (x.in_cross[i]) continue;
    if (s.door_line > 0 && s.door_line < lv && !door[i])
      f->WallV(i, s.door_line - 1);
    // Back to back with the next band (its own walls face its corridor).
    if (s.v1 < lv && s.door_line != s.v1) f->WallV(i, s.v1 - 1);
  }
  for (int i = 0; i < lu; ++i) {
    if (!x.in_cross[i]) continue;
    for (int vv = s.v0; vv < s.v1; ++vv) {
      if (i > 0 && !x.in_cross[i - 1]) f->WallU(i - 1, vv);
      if (i + 1 < lu && !x.in_cross[i + 1]) f->WallU(i, vv);
    }
  }
}

// Corridors of `corridor` steps along u, each lined with a band of rooms on
// both sides (back to back between two corridors), joined by cross
// corridors along v (one per 25 m of length, at least one) that cut through
// the bands; every room has one door onto its corridor.
void Corridors(const GeneratorConfig& g, double step, Rng& rng, Layout* l) {
  const int c = StepsIn(g.corridor, step);
  const GeneratorConfig::RoomSteps rooms = g.RoomStepsAt(step);
  const int m = rooms.min, big = rooms.max;
  const int d = StepsIn(g.door, step);
  AIA_CHECK(c >= 1 && d >= 1);
  Frame f{l, rng.Bernoulli(0.5)};
  AIA_CHECK(f.Lu() >= c + m && f.Lv() >= c + m);  // Scenario::Validate
  const std::vector<Strip> strips = Strips(f.Lv(), c, m, big, rng);
  const CrossCorridors cross = Cross(f.Lu(), c, m, step, rng);
  for (const Strip& s : strips)
    if (!s.corridor) BandWalls(s, cross, m, big, d, rng, &f);
}

// ---------------------------------------------------------------- cave ---

// A cellular automaton on cells of `cell` steps: rock drawn with
// probability `fill`, then `smoothing` passes of the 4-5 rule (outside the
// workspace counts as rock); the largest 4-connected open part is kept and
// the others filled.
int Cave(const Scenario& s, Rng& rng, Layout* l) {
  const GeneratorConfig& g = *s.workspace.obstacles.generator;
  const int k = std::max(1, StepsIn(g.cell, s.robots.step));
  const int cx = (l->nx + k - 1) / k, cy = (l->ny + k - 1) / k;
  const std::size_t n = static_cast<std::size_t>(cx) * cy;
  std::vector<std::uint8_t> rock(n), next(n);
  for (std::uint8_t& r : rock) r = rng.Bernoulli(g.fill) ? 1 : 0;
  for (int pass = 0; pass < g.smoothing; ++pass) {
    for (int y = 0; y < cy; ++y) {
      for (int x = 0; x < cx; ++x) {
        int count = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            count += (xx < 0 || yy < 0 || xx >= cx || yy >= cy)
                         ? 1
                         : rock[static_cast<std::size_t>(yy) * cx + xx];
          }
        next[static_cast<std::size_t>(y) * cx + x] = count >= 5 ? 1 : 0;
      }
    }
    rock.swap(next);
  }
  // Open parts by flood fill; the first largest in scan order is kept.
  std::vector<int> part(n, -1), stack;
  int best = -1, best_size = 0, parts = 0;
  for (std::size_t start = 0; start < n; ++start) {
    if (rock[start] || part[start] >= 0) continue;
    int size = 0;
    part[start] = parts;
    stack.assign(1, static_cast<int>(start));
    while (!stack.empty()) {
      const int c = stack.back();
      stack.pop_back();
      ++size;
      const int x = c % cx, y = c / cx;
      const int around[4][2] = {{x + 1, y}, {x - 1, y}, {x, y + 1}, {x, y - 1}};
      for (const auto& [xx, yy] : around) {
        if (xx < 0 || yy < 0 || xx >= cx || yy >= cy) continue;
        const int j = yy * cx + xx;
        if (!rock[j] && part[j] < 0) {
          part[j] = parts;
          stack.push_back(j);
        }
      }
    }
    if (size > best_size) best = parts, best_size = size;
    ++parts;
  }
  if (best < 0)
    throw s.ErrorAt(
        kKey, "the cave has no open cell after " + std::to_string(g.smoothing) +
                  " smoothing passes with fill " + FormatNumber(g.fill) +
                  " on " + std::to_string(cx) + " x " + std::to_string(cy) +
                  " cells" +
                  (g.fill > 0.0 && std::min(cx, cy) > 3
                       ? " (a lower fill)"
                       : " (a cave a few cells across turns to rock as it is "
                         "smoothed: a smaller cell, a wider workspace or "
                         "fewer smoothing passes)"));
  int free_points = 0;
  for (int iy = 0; iy < l->ny; ++iy) {
    for (int ix = 0; ix < l->nx; ++ix) {
      const std::size_t c = static_cast<std::size_t>(iy / k) * cx + ix / k;
      const bool solid = part[c] != best;
      l->rock[l->At(ix, iy)] = solid ? 1 : 0;
      free_points += solid ? 0 : 1;
    }
  }
  return free_points;
}

// ------------------------------------------------------------ boxes ---

// The layout as an image (row 0 on top, dark = solid) whose pixel columns
// and rows span [xs[i], xs[i + 1]] and [ys[j], ys[j + 1]] metres, merged into
// boxes by BoxesFromImage in pixel units and mapped to metres. More than
// `max_boxes` boxes: the merge stops early.
std::vector<Box> ImageBoxes(const std::vector<std::uint8_t>& solid, int cols,
                            int rows, const std::vector<double>& xs,
                            const std::vector<double>& ys,
                            std::size_t max_boxes) {
  std::vector<std::uint8_t> image(solid.size());
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      image[static_cast<std::size_t>(rows - 1 - r) * cols + c] =
          solid[static_cast<std::size_t>(r) * cols + c] ? 0 : 255;
  const std::vector<Box> pixels =
      BoxesFromImage(image, cols, rows, Vec2(cols, rows), 0.5, max_boxes);
  std::vector<Box> boxes;
  boxes.reserve(pixels.size());
  for (const Box& b : pixels) {
    const Box box{Vec2(xs[std::lround(b.lo.x())], ys[std::lround(b.lo.y())]),
                  Vec2(xs[std::lround(b.hi.x())], ys[std::lround(b.hi.y())])};
    if (box.hi.x() > box.lo.x() && box.hi.y() > box.lo.y())
      boxes.push_back(box);
  }
  return boxes;
}

// Thin walls: pixel column 2i is the line x = i step (wall thick), 2i + 1
// the inside of cell column i; so for rows. A wall pixel is solid when its
// edge has a wall or touches rock; a corner pixel when a wall pixel next to
// it is (so walls join and end t / 2 past their last edge). The border
// lines are the workspace's own walls, except that a strip narrower than a
// step left beyond the last lattice cell is filled.
std::vector<Box> WallBoxes(const Layout& l, const Vec2& ws, double step,
                           double t, std::size_t max_boxes) {
  const int nx = l.nx, ny = l.ny;
  const bool strip_x = nx * step < ws.x() - 1e-9,
             strip_y = ny * step < ws.y() - 1e-9;
  const int cols = 2 * nx + 1, rows = 2 * ny + 1;
  std::vector<std::uint8_t> solid(static_cast<std::size_t>(cols) * rows, 0);
  const auto px = [&](int c, int r) -> std::uint8_t& {
    return solid[static_cast<std::size_t>(r) * cols + c];
  };
  const auto rock = [&](int ix, int iy) {
    return ix >= 0 && iy >= 0 && ix < nx && iy < ny && l.rock[l.At(ix, iy)];
  };
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix) px(2 * ix + 1, 2 * iy + 1) = rock(ix, iy);
  for (int iy = 0; iy < ny; ++iy) {  // lines x = i step
    for (int i = 0; i <= nx; ++i) {
      const bool wall = i > 0 && i < nx && l.east[l.At(i - 1, iy)];
      px(2 * i, 2 * iy + 1) =
          wall || rock(i - 1, iy) || rock(i, iy) || (i == nx && strip_x);
    }
  }
  for (int j = 0; j <= ny; ++j) {  // lines y = j step
    for (int ix = 0; ix < nx; ++ix) {
      const bool wall = j > 0 && j < ny && l.north[l.At(ix, j - 1)];
      px(2 * ix + 1, 2 * j) =
          wall || rock(ix, j - 1) || rock(ix, j) || (j == ny && strip_y);
    }
  }
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      const int c = 2 * i, r = 2 * j;
      px(c, r) = (r > 0 && px(c, r - 1)) || (r + 1 < rows && px(c, r + 1)) ||
                 (c > 0 && px(c - 1, r)) || (c + 1 < cols && px(c + 1, r)) ||
                 (i == nx && strip_x) || (j == ny && strip_y);
    }
  }
  const auto edges = [&](int n, double size) {
    std::vector<double> e(2 * n + 2);
    for (int i = 0; i <= n; ++i) {
      e[2 * i] = std::max(0.0, i * step - t / 2);
      e[2 * i + 1] = i * step + t / 2;
    }
    e[2 * n + 1] = size;
    return e;
  };
  return ImageBoxes(solid, cols, rows, edges(nx, ws.x()), edges(ny, ws.y()),
                    max_boxes);
}

// Rock only: one pixel per lattice cell, plus the strip beyond the last one
// (filled).
std::vector<Box> RockBoxes(const Layout& l, const Vec2& ws, double step,
                           std::size_t max_boxes) {
  const bool strip_x = l.nx * step < ws.x() - 1e-9,
             strip_y = l.ny * step < ws.y() - 1e-9;
  const int cols = l.nx + (strip_x ? 1 : 0), rows = l.ny + (strip_y ? 1 : 0);
  std::vector<std::uint8_t> solid(static_cast<std::size_t>(cols) * rows, 1);
  for (int iy = 0; iy < l.ny; ++iy)
    for (int ix = 0; ix < l.nx; ++ix)
      solid[static_cast<std::size_t>(iy) * cols + ix] = l.rock[l.At(ix, iy)];
  const auto edges = [&](int n, int count, double size) {
    std::vector<double> e(count + 1);
    for (int i = 0; i <= n; ++i) e[i] = i * step;
    e[count] = size;
    return e;
  };
  return ImageBoxes(solid, cols, rows, edges(l.nx, cols, ws.x()),
                    edges(l.ny, rows, ws.y()), max_boxes);
}

}  // namespace

GeneratedObstacles GenerateObstacles(const Scenario& s) {
  AIA_CHECK(s.workspace.obstacles.generator.has_value());
  const GeneratorConfig& g = *s.workspace.obstacles.generator;
  const Vec2& ws = s.workspace.size;
  const double step = s.robots.step;
  Layout l(StepsIn(ws.x(), step), StepsIn(ws.y(), step));
  GeneratedObstacles out;
  if (l.nx == 0 || l.ny == 0) return out;  // no lattice point to connect
  Rng rng(s.seed, "obstacles.generator");
  out.free_points = l.nx * l.ny;
  switch (g.type) {
    case GeneratorType::kMaze:
      Maze(g, step, rng, &l);
      break;
    case GeneratorType::kRooms:
      Rooms(g, step, rng, &l);
      break;
    case GeneratorType::kCorridors:
      Corridors(g, step, rng, &l);
      break;
    case GeneratorType::kCave:
      out.free_points = Cave(s, rng, &l);
      break;
  }
  const long others = static_cast<long>(s.robots.count) + s.NumTargets();
  const std::size_t max_boxes =
      static_cast<std::size_t>(std::max(0L, kMaxBodies - others));
  out.boxes = g.HasWalls() ? WallBoxes(l, ws, step, g.wall, max_boxes)
                           : RockBoxes(l, ws, step, max_boxes);
  if (out.boxes.size() > max_boxes) {
    throw s.ErrorAt(
        kKey, "the generated " + std::string(GeneratorTypeName(g.type)) +
                  " makes more than " + std::to_string(max_boxes) +
                  " obstacle boxes, which with " +
                  std::to_string(s.robots.count) + " robots and " +
                  std::to_string(s.NumTargets()) + " targets passes the " +
                  std::to_string(kMaxBodies) +
                  " bodies aia simulates (a smaller workspace, or larger "
                  "corridors, rooms or cave cells)");
  }
  return out;
}

void CheckGeneratedLattice(const Scenario& s,
                           const GeneratedObstacles& generated,
                           const Lattice& lattice) {
  int reached = 0;
  if (lattice.NumFree() > 0) {
    int source = 0;
    while (!lattice.Free(source)) ++source;
    std::vector<int> dist, queue;
    BfsDistances(lattice, &source, 1, &dist, &queue);
    for (int d : dist) reached += d >= 0 ? 1 : 0;
  }
  if (lattice.NumFree() == generated.free_points &&
      reached == lattice.NumFree())
    return;
  const GeneratorConfig& g = *s.workspace.obstacles.generator;
  throw s.ErrorAt(
      kKey, "the generated " + std::string(GeneratorTypeName(g.type)) +
                " is not connected for the robots: " + std::to_string(reached) +
                " of its " + std::to_string(lattice.NumFree()) +
                " free lattice points are reachable from the first (its "
                "layout leaves " +
                std::to_string(generated.free_points) +
                " free, all connected); this is a generator bug, please "
                "report it with the scenario and seed");
}

}  // namespace aia
