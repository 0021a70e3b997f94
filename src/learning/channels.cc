#include "aia/learning/channels.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <queue>
#include <unordered_map>
#include <utility>

#include "aia/core/check.h"
#include "aia/core/geometry.h"

namespace aia {

namespace {

std::atomic<std::uint64_t> renderers_made{0};

}  // namespace

ChannelParams AtLatticeStep(const ChannelParams& model, double step) {
  if (step == model.cell || !(step > 0.0)) return model;
  ChannelParams p = model;
  const double scale = step / model.cell;
  p.cell = step;
  p.geodesic_length *= scale;
  p.reach_detour *= scale;
  p.reach_broad *= scale;
  return p;
}

ChannelParams AtSensorRange(const ChannelParams& model, double range) {
  ChannelParams p = model;
  if (range > 0.0 && range < p.observe_range) p.observe_range = range;
  return p;
}

std::string ChannelGridProblem(const Vec2& size, const ChannelParams& params) {
  // As MakeHeatmapGrid sizes its grids.
  const double nx = std::ceil(size.x() / params.cell - 1e-9),
               ny = std::ceil(size.y() / params.cell - 1e-9);
  if (nx * ny <= kMaxChannelPixels) return "";
  char text[320];
  std::snprintf(text, sizeof text,
                "the channels' grids cover the workspace [%g, %g] at their "
                "%g m cell: %.0f x %.0f pixels, beyond the %g (about %.0f "
                "GB) a renderer may keep; a smaller workspace, or a model "
                "(or channel settings) with a larger cell",
                size.x(), size.y(), params.cell, nx, ny, kMaxChannelPixels,
                kMaxChannelPixels * 70.0 / 1e9);
  return text;
}

ChannelRenderer::ChannelRenderer(const Grid<std::uint8_t>& occupancy,
                                 const Vec2& size, const ChannelParams& params,
                                 const Lattice* lattice)
    : params_(params), size_(size), observation_owner_(++renderers_made) {
  AIA_CHECK(params.cell > 0.0 && params.window > 0 && params.blur >= 0.0 &&
            params.cutoff > 0.0);
  AIA_CHECK_MSG(!params.geodesic || (lattice && params.geodesic_length > 0.0),
                "the geodesic channel needs the map's lattice");
  AIA_CHECK_MSG(ChannelGridProblem(size, params).empty(),
                "callers refuse such a workspace first (ChannelGridProblem)");
  occupancy_ = MakeHeatmapGrid(size, params.cell);
  heat_ = occupancy_;
  // Share of the fine cells (by their centres) inside each pixel that are
  // occupied; a pixel holding no fine centre takes the fine cell under its
  // own centre.
  Grid<float> count(occupancy_.nx(), occupancy_.ny(), params.cell, 0.0f);
  for (int fy = 0; fy < occupancy.ny(); ++fy) {
    for (int fx = 0; fx < occupancy.nx(); ++fx) {
      int ix = 0, iy = 0;
      occupancy_.CellOf(occupancy.CellCenter(fx, fy), &ix, &iy);
      count(ix, iy) += 1.0f;
      if (occupancy(fx, fy)) occupancy_(ix, iy) += 1.0f;
    }
  }
  for (int iy = 0; iy < occupancy_.ny(); ++iy) {
    for (int ix = 0; ix < occupancy_.nx(); ++ix) {
      if (count(ix, iy) > 0.0f) {
        occupancy_(ix, iy) /= count(ix, iy);
      } else if (occupancy.nx() > 0 && occupancy.ny() > 0) {
        int fx = 0, fy = 0;
        occupancy.CellOf(occupancy_.CellCenter(ix, iy), &fx, &fy);
        occupancy_(ix, iy) = occupancy(fx, fy) ? 1.0f : 0.0f;
      }
    }
  }
  if (params.geodesic) {
    AIA_CHECK(params.observe_range > 0.0);
    fine_ = occupancy;
    // A pixel's lattice point is the one nearest its centre; a pixel step is
    // a valid move when both pixels' points are free and are the same point
    // or one lattice move apart.
    const int nx = occupancy_.nx(), ny = occupancy_.ny();
    std::vector<int> point(static_cast<std::size_t>(nx) * ny);
    for (int iy = 0; iy < ny; ++iy)
      for (int ix = 0; ix < nx; ++ix)
        point[occupancy_.Index(ix, iy)] =
            lattice->NearestPoint(occupancy_.CellCenter(ix, iy));
    moves_.assign(point.size(), 0);
    for (int iy = 0; iy < ny; ++iy) {
      for (int ix = 0; ix < nx; ++ix) {
        const int q = point[occupancy_.Index(ix, iy)];
        if (!lattice->Free(q)) continue;
        for (Move m : kMoves) {
          const auto d = MoveDelta(m);
          const int jx = ix + d[0], jy = iy + d[1];
          if (!occupancy_.InBounds(jx, jy)) continue;
          const int r = point[occupancy_.Index(jx, jy)];
          if (lattice->Free(r) && (r == q || lattice->Next(q, m) == r))
            moves_[occupancy_.Index(ix, iy)] |= 1u << static_cast<int>(m);
        }
      }
    }
  }
  if (params.frame == ChannelFrame::kGlobal) {
    height_ = occupancy_.ny();
    width_ = occupancy_.nx();
  } else {
    height_ = width_ = params.window;
  }
  if (params.geodesic) {  // as ReachRegion computes it
    const double cell = params_.cell;
    const float decay =
        static_cast<float>(std::exp(-cell / params_.geodesic_length));
    decay_pow_.resize(occupancy_.nx() + occupancy_.ny() + 1);
    for (std::size_t d = 0; d < decay_pow_.size(); ++d)
      decay_pow_[d] = std::pow(decay, static_cast<int>(d));
  }
}

bool ChannelRenderer::ImagePixel(const Vec2& self, const Vec2& p, int* u,
                                 int* v) const {
  int px = 0, py = 0;
  occupancy_.CellOf(p, &px, &py);
  if (params_.frame == ChannelFrame::kCentred) {
    int cx = 0, cy = 0;
    occupancy_.CellOf(self, &cx, &cy);
    px -= cx - params_.window / 2;
    py -= cy - params_.window / 2;
  }
  *u = px;
  *v = py;
  return px >= 0 && py >= 0 && px < width_ && py < height_;
}

HeatmapParams ChannelRenderer::Heatmap(double eps) const {
  HeatmapParams hp;
  hp.eps = eps;
  hp.blur = params_.blur;
  hp.cutoff = params_.cutoff;
  return hp;
}

void ChannelRenderer::Render(const Vec2& self,
                             const std::vector<Vec2>& neighbours,
                             const std::vector<HeatSource>& targets,
                             const std::vector<double>& log_det_prior,
                             double eps, float* out,
                             const RobotMemory& memory) {
  ProjectHeatmap(targets, log_det_prior, Heatmap(eps), &heat_);
  RenderWithHeat(self, neighbours, heat_, &targets, &log_det_prior, eps, out,
                 memory);
}

namespace {

// Folds one map row (nx cells) onto the window row h (w pixels, pixel 0 at
// map column x0): the cells left of the window onto its first pixel, those
// right of it onto its last, the rest onto their own; each pixel keeps the
// largest heat (0 at least).
void FoldMapRow(const float* row, int nx, int x0, int w, float* h) {
  const int mid0 = std::clamp(x0, 0, nx), mid1 = std::clamp(x0 + w, 0, nx);
  float left = 0.0f, right = 0.0f;
  for (int gx = 0; gx < mid0; ++gx) left = std::max(left, row[gx]);
  for (int gx = mid1; gx < nx; ++gx) right = std::max(right, row[gx]);
  h[0] = std::max(h[0], left);
  h[w - 1] = std::max(h[w - 1], right);
  for (int gx = mid0; gx < mid1; ++gx)
    h[gx - x0] = std::max(h[gx - x0], row[gx]);
}

}  // namespace

void HeatFold::Build(const Grid<float>& heat) {
  heat_ = &heat;
  nx_ = heat.nx();
  ny_ = heat.ny();
  const std::size_t wide = static_cast<std::size_t>(nx_ + 1) * ny_;
  const std::size_t cells = static_cast<std::size_t>(nx_) * ny_;
  row_before_.resize(wide);
  row_from_.resize(wide);
  top_before_.resize(wide);
  top_from_.resize(wide);
  bottom_before_.resize(wide);
  bottom_from_.resize(wide);
  top_.resize(cells);
  bottom_.resize(cells);
  const float* data = heat.data().data();
  const int w = nx_ + 1;
  for (int y = 0; y < ny_; ++y) {
    const float* row = data + static_cast<std::size_t>(y) * nx_;
    float* before = row_before_.data() + static_cast<std::size_t>(y) * w;
    float* from = row_from_.data() + static_cast<std::size_t>(y) * w;
    before[0] = 0.0f;
    for (int x = 0; x < nx_; ++x) before[x + 1] = std::max(before[x], row[x]);
    from[nx_] = 0.0f;
    for (int x = nx_ - 1; x >= 0; --x) from[x] = std::max(from[x + 1], row[x]);
  }
  // Rows [0, y] (down, from the top) and [y, ny) (up, from the bottom): row
  // y's maxima with those of the row before it that way (prev < 0: none).
  const auto running = [&](int y, int prev, std::vector<float>* cols,
                           std::vector<float>* before,
                           std::vector<float>* from) {
    const std::size_t r = static_cast<std::size_t>(y);
    const std::size_t p = static_cast<std::size_t>(std::max(prev, 0));
    const float* row = data + r * nx_;
    for (int x = 0; x < nx_; ++x)
      (*cols)[r * nx_ + x] =
          prev < 0 ? row[x] : std::max((*cols)[p * nx_ + x], row[x]);
    for (int x = 0; x <= nx_; ++x) {
      (*before)[r * w + x] =
          prev < 0 ? row_before_[r * w + x]
                   : std::max((*before)[p * w + x], row_before_[r * w + x]);
      (*from)[r * w + x] =
          prev < 0 ? row_from_[r * w + x]
                   : std::max((*from)[p * w + x], row_from_[r * w + x]);
    }
  };
  for (int y = 0; y < ny_; ++y)
    running(y, y - 1, &top_, &top_before_, &top_from_);
  for (int y = ny_ - 1; y >= 0; --y)
    running(y, y + 1 < ny_ ? y + 1 : -1, &bottom_, &bottom_before_,
            &bottom_from_);
}

void HeatFold::FoldRegion(int lo, int hi, int x0, int w, float* h) const {
  const int mid0 = std::clamp(x0, 0, nx_), mid1 = std::clamp(x0 + w, 0, nx_);
  const int stride = nx_ + 1;
  const float *before = nullptr, *from = nullptr, *cols = nullptr;
  if (lo == 0) {  // rows [0, hi]
    before = top_before_.data() + static_cast<std::size_t>(hi) * stride;
    from = top_from_.data() + static_cast<std::size_t>(hi) * stride;
    cols = top_.data() + static_cast<std::size_t>(hi) * nx_;
  } else if (hi == ny_ - 1) {  // rows [lo, ny)
    before = bottom_before_.data() + static_cast<std::size_t>(lo) * stride;
    from = bottom_from_.data() + static_cast<std::size_t>(lo) * stride;
    cols = bottom_.data() + static_cast<std::size_t>(lo) * nx_;
  } else {  // row lo alone
    AIA_CHECK(lo == hi);
    before = row_before_.data() + static_cast<std::size_t>(lo) * stride;
    from = row_from_.data() + static_cast<std::size_t>(lo) * stride;
    cols = heat_->data().data() + static_cast<std::size_t>(lo) * nx_;
  }
  h[0] = std::max(h[0], before[mid0]);
  h[w - 1] = std::max(h[w - 1], from[mid1]);
  for (int gx = mid0; gx < mid1; ++gx)
    h[gx - x0] = std::max(h[gx - x0], cols[gx]);
}

void HeatFold::Fold(int x0, int y0, int w, float* out) const {
  AIA_CHECK(heat_ != nullptr && w > 0);
  for (int r = 0; r < w; ++r) {
    // The map rows that fold onto window row r.
    const int lo = std::max(0, r == 0 ? 0 : y0 + r);
    const int hi = std::min(ny_ - 1, r == w - 1 ? ny_ - 1 : y0 + r);
    if (lo <= hi)
      FoldRegion(lo, hi, x0, w, out + static_cast<std::size_t>(r) * w);
  }
}

void HeatFold::FoldEdited(int x0, int y0, int w,
                          const std::vector<HeatEdit>& edits,
                          float* out) const {
  AIA_CHECK(heat_ != nullptr && w > 0);
  // The map rows an edit touches, counted up to each row.
  thread_local std::vector<int> touched_before;
  thread_local std::vector<float> row;
  touched_before.assign(ny_ + 1, 0);
  for (const HeatEdit& e : edits)
    for (int y = e.stamp->y0; y < e.stamp->y0 + e.stamp->ny; ++y)
      touched_before[y + 1] = 1;
  for (int y = 0; y < ny_; ++y) touched_before[y + 1] += touched_before[y];
  const auto touched = [&](int y) {
    return touched_before[y + 1] != touched_before[y];
  };
  const float* data = heat_->data().data();
  for (int r = 0; r < w; ++r) {
    const int lo = std::max(0, r == 0 ? 0 : y0 + r);
    const int hi = std::min(ny_ - 1, r == w - 1 ? ny_ - 1 : y0 + r);
    if (lo > hi) continue;
    float* h = out + static_cast<std::size_t>(r) * w;
    if (touched_before[hi + 1] == touched_before[lo]) {
      FoldRegion(lo, hi, x0, w, h);  // no edit in these rows: as Fold
      continue;
    }
    // Row by row: an untouched one from its own tables, a touched one made
    // (the base row, then every edit of it in order) and folded whole.
    for (int gy = lo; gy <= hi; ++gy) {
      const float* cells = data + static_cast<std::size_t>(gy) * nx_;
      if (!touched(gy)) {
        FoldRegion(gy, gy, x0, w, h);
        continue;
      }
      row.assign(cells, cells + nx_);
      for (const HeatEdit& e : edits) {
        const HeatStamp& st = *e.stamp;
        if (gy < st.y0 || gy >= st.y0 + st.ny) continue;
        const float* in =
            st.values.data() + static_cast<std::size_t>(gy - st.y0) * st.nx;
        float* cell = row.data() + st.x0;
        if (e.subtract) {
          for (int x = 0; x < st.nx; ++x) cell[x] -= in[x];
        } else {
          for (int x = 0; x < st.nx; ++x) cell[x] += in[x];
        }
      }
      FoldMapRow(row.data(), nx_, x0, w, h);
    }
  }
}

void ChannelRenderer::CapNeighbours(float* nbr, std::size_t plane) const {
  if (params_.neighbour_cap <= 0) return;
  const float cap = static_cast<float>(params_.neighbour_cap);
  for (std::size_t i = 0; i < plane; ++i) nbr[i] = std::min(nbr[i], cap);
}

void ChannelRenderer::RenderWithHeat(
    const Vec2& self, const std::vector<Vec2>& neighbours,
    const Grid<float>& field, const std::vector<HeatSource>* targets,
    const std::vector<double>* log_det_prior, double eps, float* out,
    const RobotMemory& memory, const HeatFold* heat_fold,
    const std::vector<HeatEdit>* heat_edits) const {
  AIA_CHECK(field.nx() == occupancy_.nx() && field.ny() == occupancy_.ny());
  AIA_CHECK_MSG(!params_.geodesic || (targets && log_det_prior),
                "channel 4 needs the robot's belief");
  AIA_CHECK_MSG(!heat_edits || heat_edits->empty() ||
                    (heat_fold && heat_fold->heat() == &field &&
                     params_.frame == ChannelFrame::kCentred),
                "heat edits need the fold of the heatmap they edit");
  const std::size_t plane = static_cast<std::size_t>(height_) * width_;
  float* occ = out;
  float* own = out + plane;
  float* nbr = out + 2 * plane;
  float* heat = out + 3 * plane;
  std::fill(out, out + channels() * plane, 0.0f);
  const int nx = occupancy_.nx(), ny = occupancy_.ny();

  if (params_.frame == ChannelFrame::kGlobal) {
    std::copy(occupancy_.data().begin(), occupancy_.data().end(), occ);
    std::copy(field.data().begin(), field.data().end(), heat);
    int ix = 0, iy = 0;
    occupancy_.CellOf(self, &ix, &iy);
    own[occupancy_.Index(ix, iy)] = 1.0f;
    for (const Vec2& p : neighbours) {
      occupancy_.CellOf(p, &ix, &iy);
      nbr[occupancy_.Index(ix, iy)] += 1.0f;
    }
    CapNeighbours(nbr, plane);
    if (params_.geodesic)
      Reach(0, 0, self, *targets, *log_det_prior, eps, out + 4 * plane,
            memory.search);
    Trail(self, memory, out + params_.trail_channel() * plane);
    return;
  }

  const int w = params_.window;
  int cx = 0, cy = 0;
  occupancy_.CellOf(self, &cx, &cy);
  const int x0 = cx - w / 2, y0 = cy - w / 2;
  for (int v = 0; v < w; ++v) {
    const int gy = y0 + v;
    for (int u = 0; u < w; ++u) {
      const int gx = x0 + u;
      occ[v * w + u] = occupancy_.InBounds(gx, gy) ? occupancy_(gx, gy) : 1.0f;
    }
  }
  own[(w / 2) * w + w / 2] = 1.0f;
  const auto fold = [w](int g, int origin) {
    return std::clamp(g - origin, 0, w - 1);
  };
  for (const Vec2& p : neighbours) {
    int ix = 0, iy = 0;
    occupancy_.CellOf(p, &ix, &iy);
    nbr[fold(iy, y0) * w + fold(ix, x0)] += 1.0f;
  }
  CapNeighbours(nbr, plane);
  // Row by row: the cells left of the window fold onto its first column,
  // those right of it onto its last, the rest onto their own column.
  if (heat_fold && heat_fold->heat() == &field) {
    if (heat_edits && !heat_edits->empty()) {
      heat_fold->FoldEdited(x0, y0, w, *heat_edits, heat);
    } else {
      heat_fold->Fold(x0, y0, w, heat);
    }
  } else {
    for (int gy = 0; gy < ny; ++gy)
      FoldMapRow(field.data().data() + field.Index(0, gy), nx, x0, w,
                 heat + fold(gy, y0) * w);
  }
  if (params_.geodesic)
    Reach(x0, y0, self, *targets, *log_det_prior, eps, out + 4 * plane,
          memory.search);
  Trail(self, memory, out + params_.trail_channel() * plane);
}

void SetTrail(const Lattice& lattice, int here, Move last,
              RobotMemory* memory) {
  memory->moved = false;
  if (last == Move::kStay) return;
  const int from = lattice.Next(here, Opposite(last));
  memory->moved = from >= 0;
  if (from >= 0) memory->came_from = lattice.Point(from);
}

void ChannelRenderer::Trail(const Vec2& self, const RobotMemory& memory,
                            float* out) const {
  if (!params_.trail || !memory.moved) return;
  int u = 0, v = 0;
  if (ImagePixel(self, memory.came_from, &u, &v)) out[v * width_ + u] = 1.0f;
}

bool ChannelRenderer::Sees(const Vec2& a, const Vec2& b) const {
  // Samples every half fine cell (no cell is stepped over); the cell under
  // b itself is not asked (a mean estimated inside a wall is seen from
  // beside it).
  const Vec2 d = b - a;
  const double len = d.norm();
  const double step = 0.5 * fine_.cell();
  const int n = static_cast<int>(std::ceil(len / step));
  int bx = 0, by = 0;
  fine_.CellOf(b, &bx, &by);
  for (int i = 0; i < n; ++i) {
    int ix = 0, iy = 0;
    fine_.CellOf(a + d * (static_cast<double>(i) / n), &ix, &iy);
    if (ix == bx && iy == by) break;
    if (fine_(ix, iy)) return false;
  }
  return true;
}

const std::vector<int>& ChannelRenderer::ObservationPixels(
    const Vec2& x) const {
  const PointKey key = KeyOf(x);
  struct Kept {
    std::uint64_t owner = 0;
    std::unordered_map<PointKey, std::vector<int>, PointKeyHash> pixels;
  };
  thread_local Kept kept;
  if (kept.owner != observation_owner_) {
    kept.pixels.clear();
    kept.owner = observation_owner_;
  }
  const auto it = kept.pixels.find(key);
  if (it != kept.pixels.end()) return it->second;
  std::vector<int> found;
  const int nx = occupancy_.nx(), ny = occupancy_.ny();
  const int reach =
      static_cast<int>(std::ceil(params_.observe_range / params_.cell));
  const double r2 = params_.observe_range * params_.observe_range;
  int mx = 0, my = 0;
  occupancy_.CellOf(x, &mx, &my);
  for (int gy = std::max(0, my - reach); gy <= std::min(ny - 1, my + reach);
       ++gy) {
    for (int gx = std::max(0, mx - reach); gx <= std::min(nx - 1, mx + reach);
         ++gx) {
      const int idx = occupancy_.Index(gx, gy);
      if (!moves_[idx]) continue;
      const Vec2 c = occupancy_.CellCenter(gx, gy);
      if ((c - x).squaredNorm() > r2 || !Sees(c, x)) continue;
      found.push_back(idx);
    }
  }
  if (kept.pixels.size() >= kObservationCacheSize) kept.pixels.clear();
  return kept.pixels.emplace(key, std::move(found)).first->second;
}

void ChannelRenderer::Reach(int x0, int y0, const Vec2& self,
                            const std::vector<HeatSource>& targets,
                            const std::vector<double>& log_det_prior,
                            double eps, float* out,
                            const SearchPointSets* search) const {
  if (params_.reach_world) {
    int sx = 0, sy = 0;
    occupancy_.CellOf(self, &sx, &sy);
    const SearchPointSets* points = params_.search ? search : nullptr;
    // `out` is channel 4; the optional channels after it follow.
    const std::size_t plane = static_cast<std::size_t>(height_) * width_;
    float* second = params_.reach_second
                        ? out + (params_.second_channel() - 4) * plane
                        : nullptr;
    ReachWorld(x0, y0, width_, height_, sx, sy, targets, log_det_prior, eps,
               out, points, params_.geodesic_length, true, second);
    if (params_.reach_broad > 0.0)
      ReachWorld(x0, y0, width_, height_, sx, sy, targets, log_det_prior, eps,
                 out + (params_.broad_channel() - 4) * plane, points,
                 params_.reach_broad, false, nullptr);
    return;
  }
  const int margin =
      params_.frame == ChannelFrame::kCentred ? params_.reach_margin : 0;
  if (margin == 0) {
    ReachRegion(x0, y0, width_, height_, targets, log_det_prior, eps, out);
    return;
  }
  // Over the window and `margin` pixels around it, then cropped and scaled
  // again.
  const int w = width_ + 2 * margin, h = height_ + 2 * margin;
  thread_local std::vector<float> region;
  region.resize(static_cast<std::size_t>(w) * h);
  ReachRegion(x0 - margin, y0 - margin, w, h, targets, log_det_prior, eps,
              region.data());
  float top = 0.0f;
  for (int v = 0; v < height_; ++v)
    for (int u = 0; u < width_; ++u) {
      const float value = region[(v + margin) * w + u + margin];
      out[v * width_ + u] = value;
      top = std::max(top, value);
    }
  if (top > 0.0f)
    for (int i = 0; i < width_ * height_; ++i) out[i] /= top;
}

namespace internal {
ChannelRenderer ExhaustiveReachWorld(const ChannelRenderer& renderer) {
  ChannelRenderer reference = renderer;
  reference.exhaustive_reach_ = true;
  return reference;
}
}  // namespace internal

namespace {

// The reach channel over the workspace is scaled at the robot's own pixel:
// a pixel whose way is d moves shorter holds exp(d / (L / cell) -
// kReachSelf), capped at 1 (ChannelRenderer::ReachWorld).
constexpr double kReachSelf = 2.0;
constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

// ReachWorld's search (see there) for one call: A* toward the window's
// pixels and the robot's, from the observation pixels of every target with
// a weight, each target entering when the search reaches a lower bound of
// its pixels' f. Its scratch is per thread, reset where the last call wrote
// it: nothing is allocated or cleared in proportion to the map once warm.
class ChannelRenderer::ReachSearch {
 public:
  // An entry: f, its cost, the pixel and the target. The heap orders by f
  // alone: entries of equal f pop in whichever order the heap holds them,
  // and the images do not depend on it (a pixel's cost is its least over
  // the targets, its second cost the least over the others, whichever way
  // ties are found; the labels of tied ways may differ, their costs not).
  // Comparing the pixel and the target too cost 3 to 4 % of the network
  // alone's policy at 1000 robots (the heap is most of this search).
  struct Entry {
    double f, c;
    int pixel, target;
  };

  // `second`: each pixel keeps its two best targets (ReachWorld's second).
  ReachSearch(const ChannelRenderer& renderer, int x0, int y0, int w, int h,
              int sx, int sy, bool second,
              const std::vector<HeatSource>& targets,
              const SearchPointSets* search);
  // Every target of weight above 0 a source, of cost -(L / cell) ln w,
  // ordered by a lower bound on its observation pixels' f.
  void AddSources(const std::vector<double>& log_det_prior, double eps,
                  double moves_per_e);
  // Settles pixels in order of f until the next entry's f passes the
  // robot's own cost (its second with `second`; self_idx: the robot's
  // pixel, -1 where it cannot stand) plus `cap`.
  void Run(double cap, int self_idx);

  // Per global pixel: the least cost and (with `second`) the second's;
  // infinite where nothing settled.
  const std::vector<double>& cost() const { return s_.cost; }
  const std::vector<double>& cost2() const { return s_.cost2; }
  // The robot's own costs, once settled (else infinite).
  double self_cost() const { return self_cost_; }
  double self_cost2() const { return self_cost2_; }

 private:
  struct Scratch {
    std::vector<double> cost, cost2;
    std::vector<int> label, label2, touched;
    std::vector<Entry> heap;
    std::vector<std::pair<double, int>> sources;
    std::vector<double> start;
  };
  struct Later {
    bool operator()(const Entry& a, const Entry& b) const { return a.f > b.f; }
  };
  struct Greater {
    bool operator()(const std::pair<double, int>& a,
                    const std::pair<double, int>& b) const {
      return a > b;
    }
  };

  // This thread's scratch, reset for a map of `total` pixels.
  static Scratch& ResetScratch(std::size_t total);
  // g(p): the moves from global pixel (gx, gy) to the nearest pixel of the
  // window or the robot's on an empty lattice (0 when exhaustive).
  int Bound(int gx, int gy) const;
  // A way of cost c from target k reaches pixel j; whether it is kept.
  bool Improve(int j, double c, int k);
  // Target k's points: its search points, else its mean.
  std::pair<const Vec2*, std::size_t> Points(std::size_t k) const;
  // Target k's observation pixels enter at its start cost.
  void Seed(int k);
  // The source of least bound enters.
  void SeedNext();

  const ChannelRenderer& r_;
  const int nx_;
  const int x0_, y0_, w_, h_, sx_, sy_;
  const bool second_;
  const bool exhaustive_;
  const bool self_inside_;
  const std::vector<HeatSource>& targets_;
  const SearchPointSets* search_;
  Scratch& s_;
  double self_cost_ = kInf, self_cost2_ = kInf;
};

ChannelRenderer::ReachSearch::ReachSearch(
    const ChannelRenderer& renderer, int x0, int y0, int w, int h, int sx,
    int sy, bool second, const std::vector<HeatSource>& targets,
    const SearchPointSets* search)
    : r_(renderer),
      nx_(renderer.occupancy_.nx()),
      x0_(x0),
      y0_(y0),
      w_(w),
      h_(h),
      sx_(sx),
      sy_(sy),
      second_(second),
      exhaustive_(renderer.exhaustive_reach_),
      self_inside_(sx >= x0 && sy >= y0 && sx < x0 + w && sy < y0 + h),
      targets_(targets),
      search_(search),
      s_(ResetScratch(static_cast<std::size_t>(renderer.occupancy_.nx()) *
                      renderer.occupancy_.ny())) {}

ChannelRenderer::ReachSearch::Scratch&
ChannelRenderer::ReachSearch::ResetScratch(std::size_t total) {
  thread_local Scratch s;
  if (s.cost.size() != total) {
    s.cost.assign(total, kInf);
    s.cost2.assign(total, kInf);
    s.label.assign(total, -1);
    s.label2.assign(total, -1);
  } else {
    for (const int j : s.touched) {
      s.cost[j] = s.cost2[j] = kInf;
      s.label[j] = s.label2[j] = -1;
    }
  }
  s.touched.clear();
  s.heap.clear();
  s.sources.clear();
  return s;
}

int ChannelRenderer::ReachSearch::Bound(int gx, int gy) const {
  if (exhaustive_) return 0;
  const int dx =
      gx < x0_ ? x0_ - gx : (gx >= x0_ + w_ ? gx - (x0_ + w_ - 1) : 0);
  const int dy =
      gy < y0_ ? y0_ - gy : (gy >= y0_ + h_ ? gy - (y0_ + h_ - 1) : 0);
  const int to_window = dx + dy;
  if (self_inside_) return to_window;
  return std::min(to_window, std::abs(gx - sx_) + std::abs(gy - sy_));
}

// Without `second`: kept if it is j's least. With it: kept if it is j's
// least or its least from any other target than the least's (each pixel
// holds its two best targets, never one twice).
bool ChannelRenderer::ReachSearch::Improve(int j, double c, int k) {
  std::vector<double>& cost = s_.cost;
  std::vector<double>& cost2 = s_.cost2;
  std::vector<int>& label = s_.label;
  std::vector<int>& label2 = s_.label2;
  if (cost[j] == kInf) s_.touched.push_back(j);
  if (!second_ || k == label[j]) {
    if (c >= cost[j]) return false;
    cost[j] = c;
    if (second_) label[j] = k;
  } else if (c < cost[j]) {
    cost2[j] = cost[j];
    label2[j] = label[j];
    cost[j] = c;
    label[j] = k;
  } else if (c < cost2[j]) {
    cost2[j] = c;
    label2[j] = k;
  } else {
    return false;
  }
  s_.heap.push_back({c + Bound(j % nx_, j / nx_), c, j, k});
  std::push_heap(s_.heap.begin(), s_.heap.end(), Later());
  return true;
}

std::pair<const Vec2*, std::size_t> ChannelRenderer::ReachSearch::Points(
    std::size_t k) const {
  if (search_ && k < search_->size() && !(*search_)[k].empty())
    return {(*search_)[k].data(), (*search_)[k].size()};
  return {&targets_[k].mean, 1};
}

// The targets in order of a lower bound on their observation pixels' f: c0
// plus g at the point, less the most an observation pixel can be nearer
// (observe_range in pixels, along each axis). A heap, least bound first:
// the search takes a few of them.
void ChannelRenderer::ReachSearch::AddSources(
    const std::vector<double>& log_det_prior, double eps, double moves_per_e) {
  std::vector<std::pair<double, int>>& sources = s_.sources;
  std::vector<double>& start = s_.start;
  const int observe =
      static_cast<int>(std::ceil(r_.params_.observe_range / r_.params_.cell));
  start.assign(targets_.size(), kInf);
  const double log_eps = std::log(eps);
  for (std::size_t k = 0; k < targets_.size(); ++k) {
    const double wk =
        HeatWeightOfLog(targets_[k].log_det, log_det_prior[k], log_eps);
    if (wk <= 0.0) continue;
    // A weight of 1 (each target the robot has not measured) needs no log.
    start[k] = -moves_per_e * (wk == 1.0 ? 0.0 : std::log(wk));
    int near = std::numeric_limits<int>::max();
    const auto [at, count] = Points(k);
    for (std::size_t a = 0; a < count && near > 0; ++a) {
      int mx = 0, my = 0;
      r_.occupancy_.CellOf(at[a], &mx, &my);
      near = std::min(near, std::max(0, Bound(mx, my) - 2 * observe));
    }
    sources.emplace_back(start[k] + near, static_cast<int>(k));
  }
  std::make_heap(sources.begin(), sources.end(), Greater());
}

void ChannelRenderer::ReachSearch::Seed(int k) {
  const auto [at, count] = Points(k);
  for (std::size_t a = 0; a < count; ++a)
    for (const int idx : r_.ObservationPixels(at[a]))
      Improve(idx, s_.start[k], k);
}

void ChannelRenderer::ReachSearch::SeedNext() {
  std::vector<std::pair<double, int>>& sources = s_.sources;
  std::pop_heap(sources.begin(), sources.end(), Greater());
  const int k = sources.back().second;
  sources.pop_back();
  Seed(k);
}

void ChannelRenderer::ReachSearch::Run(double cap, int self_idx) {
  std::vector<Entry>& heap = s_.heap;
  std::vector<std::pair<double, int>>& sources = s_.sources;
  const std::vector<double>& cost = s_.cost;
  const std::vector<double>& cost2 = s_.cost2;
  const std::vector<int>& label = s_.label;
  const std::vector<int>& label2 = s_.label2;
  const std::vector<std::uint8_t>& moves = r_.moves_;
  // The reference (internal::ExhaustiveReachWorld) is the search before the
  // bound: every source at once, stopping at the threshold itself. The
  // bounded search stops one move later: f = cost + g is rounded once
  // where a way's cost adds 1.0 a move, so a pixel on the least way to one
  // at the threshold could read a unit in the last place above it; what
  // settles past the threshold is never read.
  const double slack = exhaustive_ ? 0.0 : 1.0;
  if (exhaustive_)
    while (!sources.empty()) SeedNext();
  while (true) {
    const double stop = (second_ ? self_cost2_ : self_cost_) + cap + slack;
    // Every target whose bound is at most the next entry's f (one at a
    // time: each may bring a nearer next entry).
    while (!sources.empty() &&
           sources.front().first <=
               std::min(heap.empty() ? kInf : heap.front().f, stop))
      SeedNext();
    if (heap.empty() || heap.front().f > stop) break;
    std::pop_heap(heap.begin(), heap.end(), Later());
    const Entry e = heap.back();
    heap.pop_back();
    const double c = e.c;
    const int idx = e.pixel, k = e.target;
    const bool best = c == cost[idx] && (!second_ || k == label[idx]);
    if (!best && !(second_ && c == cost2[idx] && k == label2[idx]))
      continue;  // stale
    if (idx == self_idx) (best ? self_cost_ : self_cost2_) = c;
    const unsigned m = moves[idx];
    const int gx = idx % nx_, gy = idx / nx_;
    for (Move move : kMoves) {
      if (!(m & (1u << static_cast<int>(move)))) continue;
      const auto d = MoveDelta(move);
      const int j = r_.occupancy_.Index(gx + d[0], gy + d[1]);
      if (moves[j]) Improve(j, c + 1.0, k);
    }
  }
}

void ChannelRenderer::ReachWorld(int x0, int y0, int w, int h, int sx, int sy,
                                 const std::vector<HeatSource>& targets,
                                 const std::vector<double>& log_det_prior,
                                 double eps, float* out,
                                 const SearchPointSets* search, double length,
                                 bool detour, float* second) const {
  // cost(p) = min over observation pixels q of d(p, q) - (L / cell) ln w(q),
  // d in valid moves: the log of G(p) = max_q w(q) exp(-d(p, q) cell / L) up
  // to the factor -cell / L. Each pixel settles once (with `second`, once
  // per each of its two best targets).
  //
  // Only the window's pixels and the robot's are read, so the search is A*
  // toward them (ReachSearch): entries pop in order of f = cost + g(p), g(p)
  // the moves from p to the nearest of those pixels on an empty lattice (a
  // lower bound on the way there that changes by at most 1 a move), and a
  // target's observation pixels enter only when the search reaches a lower
  // bound of their f. Every pixel on a least way to a window pixel of cost
  // c has f <= c, so each pixel the images read settles, with the cost a
  // search over the whole workspace gives it, before the first entry past
  // the threshold below; what the search visits grows with the way from
  // the robot to its nearest targets, not with the workspace or the number
  // of targets.
  const int nx = occupancy_.nx(), ny = occupancy_.ny();
  const double moves_per_e = length / params_.cell;
  ReachSearch reach(*this, x0, y0, w, h, sx, sy, second != nullptr, targets,
                    search);
  reach.AddSources(log_det_prior, eps, moves_per_e);
  // Pixels far above the robot's cost (below 1e-6, kReachSelf) are left at
  // 0: the search stops there, its cost the area between the robot and the
  // nearest observation pixels, not the map's.
  const double cap = moves_per_e * (std::log(1e6) - kReachSelf);
  const bool self_free = sx >= 0 && sy >= 0 && sx < nx && sy < ny &&
                         moves_[occupancy_.Index(sx, sy)] != 0;
  reach.Run(cap, self_free ? occupancy_.Index(sx, sy) : -1);
  const bool dim = detour && params_.reach_detour > 0.0 && self_free;
  ReachImage(x0, y0, w, h, reach.cost(), reach.self_cost(), moves_per_e, cap,
             out);
  if (dim) DimByDetour(x0, y0, w, h, sx, sy, out);
  if (second) {
    ReachImage(x0, y0, w, h, reach.cost2(), reach.self_cost2(), moves_per_e,
               cap, second);
    if (dim) DimByDetour(x0, y0, w, h, sx, sy, second);
  }
}

void ChannelRenderer::ReachImage(int x0, int y0, int w, int h,
                                 const std::vector<double>& costs, double self,
                                 double moves_per_e, double cap,
                                 float* out) const {
  const int nx = occupancy_.nx(), ny = occupancy_.ny();
  // Where no way leads to the robot: scaled to the window's least cost.
  double ref = self, offset = kReachSelf;
  if (!std::isfinite(ref)) {
    offset = 0.0;
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) {
        const int gx = x0 + u, gy = y0 + v;
        if (gx < 0 || gy < 0 || gx >= nx || gy >= ny) continue;
        ref = std::min(ref, costs[occupancy_.Index(gx, gy)]);
      }
  }
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const int gx = x0 + u, gy = y0 + v;
      float value = 0.0f;
      if (gx >= 0 && gy >= 0 && gx < nx && gy < ny && std::isfinite(ref)) {
        const double c = costs[occupancy_.Index(gx, gy)];
        if (c <= ref + cap)  // settled (an unsettled pixel: below 1e-6)
          value = static_cast<float>(
              std::min(1.0, std::exp((ref - c) / moves_per_e - offset)));
      }
      out[v * w + u] = value;
    }
}

void ChannelRenderer::DimByDetour(int x0, int y0, int w, int h, int sx, int sy,
                                  float* out) const {
  // Breadth-first from the robot's pixel over the valid moves inside the
  // window: m(p) moves; a pixel never reached reads 0. Scratch per thread.
  const int nx = occupancy_.nx(), ny = occupancy_.ny();
  const int su = sx - x0, sv = sy - y0;
  if (su < 0 || sv < 0 || su >= w || sv >= h) return;
  thread_local std::vector<int> moves_to;
  thread_local std::vector<int> queue;
  moves_to.assign(static_cast<std::size_t>(w) * h, -1);
  queue.clear();
  moves_to[sv * w + su] = 0;
  queue.push_back(sv * w + su);
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const int at = queue[head];
    const int u = at % w, v = at / w;
    const unsigned m = moves_[occupancy_.Index(x0 + u, y0 + v)];
    for (Move move : kMoves) {
      if (!(m & (1u << static_cast<int>(move)))) continue;
      const auto d = MoveDelta(move);
      const int nu = u + d[0], nv = v + d[1];
      if (nu < 0 || nv < 0 || nu >= w || nv >= h) continue;
      const int next = nv * w + nu;
      if (moves_to[next] >= 0) continue;
      moves_to[next] = moves_to[at] + 1;
      queue.push_back(next);
    }
  }
  // exp(-k cell / reach_detour) for a detour of k moves, k < w + h.
  const double per_move = params_.cell / params_.reach_detour;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const int gx = x0 + u, gy = y0 + v;
      const int i = v * w + u;
      if (gx < 0 || gy < 0 || gx >= nx || gy >= ny || moves_to[i] < 0) {
        out[i] = 0.0f;
        continue;
      }
      const int detour = moves_to[i] - std::abs(u - su) - std::abs(v - sv);
      if (detour > 0)
        out[i] *= static_cast<float>(std::exp(-detour * per_move));
    }
}

namespace internal {

void SortByValueDescending(std::vector<std::pair<float, int>>* items) {
  const std::size_t n = items->size();
  if (n < 64) {
    std::sort(items->begin(), items->end(),
              [](const std::pair<float, int>& a,
                 const std::pair<float, int>& b) { return a.first > b.first; });
    return;
  }
  thread_local std::vector<std::pair<float, int>> other;
  other.resize(n);
  std::vector<std::pair<float, int>>* from = items;
  std::vector<std::pair<float, int>>* to = &other;
  const auto key = [](float value) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);
    return ~bits;  // ascending keys, descending values
  };
  for (int shift = 0; shift < 32; shift += 11) {
    std::array<std::uint32_t, 2049> start{};
    for (const auto& item : *from)
      ++start[((key(item.first) >> shift) & 2047) + 1];
    for (int b = 0; b < 2048; ++b) start[b + 1] += start[b];
    for (const auto& item : *from)
      (*to)[start[(key(item.first) >> shift) & 2047]++] = item;
    std::swap(from, to);
  }
  if (from != items) items->swap(*from);
}

}  // namespace internal

void ChannelRenderer::ReachRegion(int x0, int y0, int w, int h,
                                  const std::vector<HeatSource>& targets,
                                  const std::vector<double>& log_det_prior,
                                  double eps, float* out) const {
  // Dijkstra with the largest value first from every target's observation
  // pixels (a sorted list and a FIFO, below); a pixel a robot cannot stand on
  // (the border pixel a far observation pixel folds onto may be one) gives its
  // value to the free pixels beside it but is given nothing. Scratch per
  // thread: nothing is allocated once warm.
  const double cell = params_.cell;
  const float decay =
      static_cast<float>(std::exp(-cell / params_.geodesic_length));
  thread_local std::vector<std::pair<float, int>> ordered;  // the sources
  ordered.clear();
  const auto mask = [&](int u, int v) -> unsigned {
    const int gx = x0 + u, gy = y0 + v;
    return occupancy_.InBounds(gx, gy) ? moves_[occupancy_.Index(gx, gy)] : 0u;
  };
  const auto free = [&](int u, int v) {
    const int gx = x0 + u, gy = y0 + v;
    if (!occupancy_.InBounds(gx, gy)) return false;
    // A pixel with any valid step is free; an isolated free point has none
    // and nothing to lead anywhere.
    return moves_[occupancy_.Index(gx, gy)] != 0;
  };
  const std::size_t n = static_cast<std::size_t>(h) * w;
  std::fill(out, out + n, 0.0f);
  // Each pixel's largest source value: a smaller one from the same pixel
  // leads nowhere the larger does not lead higher (values only decay), so
  // the search starts with one entry per source pixel, not one per target
  // (hundreds of far targets fold onto a few border pixels).
  thread_local std::vector<float> source;
  thread_local std::vector<int> sources;
  source.assign(n, 0.0f);
  sources.clear();
  const auto add = [&](int u, int v, float value) {
    const int idx = v * w + u;
    if (free(u, v)) out[idx] = std::max(out[idx], value);
    if (source[idx] == 0.0f) sources.push_back(idx);
    source[idx] = std::max(source[idx], value);
  };
  const int reach = static_cast<int>(std::ceil(params_.observe_range / cell));
  const double log_eps = std::log(eps);
  // decay^d, as std::pow gives it, from a table.
  const auto decayed = [&](int d) {
    return d < static_cast<int>(decay_pow_.size()) ? decay_pow_[d]
                                                   : std::pow(decay, d);
  };
  for (std::size_t k = 0; k < targets.size(); ++k) {
    const double wk =
        HeatWeightOfLog(targets[k].log_det, log_det_prior[k], log_eps);
    if (wk <= 0.0) continue;
    int mx = 0, my = 0;
    occupancy_.CellOf(targets[k].mean, &mx, &my);
    // A target whose observation pixels all lie beyond the window: one
    // source at the border, counting the moves beyond it.
    const int mu = mx - x0, mv = my - y0;
    if (mu < -reach || mv < -reach || mu >= w + reach || mv >= h + reach) {
      const int bu = std::clamp(mu, 0, w - 1), bv = std::clamp(mv, 0, h - 1);
      const int beyond = std::abs(mu - bu) + std::abs(mv - bv) - reach;
      const float value = static_cast<float>(wk * decayed(std::max(beyond, 0)));
      if (value < 1e-6f) continue;
      add(bu, bv, value);
      continue;
    }
    for (const int idx : ObservationPixels(targets[k].mean)) {
      const int u = idx % occupancy_.nx() - x0, v = idx / occupancy_.nx() - y0;
      const int bu = std::clamp(u, 0, w - 1), bv = std::clamp(v, 0, h - 1);
      const float value =
          static_cast<float>(wk * decayed(std::abs(u - bu) + std::abs(v - bv)));
      add(bu, bv, value);
    }
  }
  // Largest value first without a heap: the sources sorted, and a FIFO of
  // the values they lead to. A value pushed is the popped one times the
  // decay, so the FIFO never rises, and taking the larger of the two heads
  // pops in Dijkstra's order (ties in any order: each pixel's value is the
  // largest over the ways to it, whichever is found first).
  for (const int idx : sources) ordered.emplace_back(source[idx], idx);
  internal::SortByValueDescending(&ordered);
  thread_local std::vector<std::pair<float, int>> fifo;
  fifo.clear();
  std::size_t next_source = 0, next_fifo = 0;
  while (next_source < ordered.size() || next_fifo < fifo.size()) {
    const bool from_sources =
        next_fifo == fifo.size() ||
        (next_source < ordered.size() &&
         ordered[next_source].first >= fifo[next_fifo].first);
    const auto [value, idx] =
        from_sources ? ordered[next_source++] : fifo[next_fifo++];
    const int u = idx % w, v = idx / w;
    const bool from_free = free(u, v);
    if (from_free && value < out[idx]) continue;  // stale
    const float next = value * decay;
    if (next < 1e-6f) continue;
    const unsigned m = from_free ? mask(u, v) : 0xFu;
    for (Move move : kMoves) {
      if (!(m & (1u << static_cast<int>(move)))) continue;
      const auto d = MoveDelta(move);
      const int ju = u + d[0], jv = v + d[1];
      if (ju < 0 || jv < 0 || ju >= w || jv >= h || !free(ju, jv)) continue;
      const int j = jv * w + ju;
      if (next > out[j]) {
        out[j] = next;
        fifo.emplace_back(next, j);
      }
    }
  }
  float top = 0.0f;
  for (std::size_t i = 0; i < n; ++i) top = std::max(top, out[i]);
  if (top > 0.0f)
    for (std::size_t i = 0; i < n; ++i) out[i] /= top;
}

}  // namespace aia
