#include "aia/estimation/heatmap.h"

#include <Eigen/LU>
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "aia/core/check.h"

namespace aia {

double HeatWeight(double log_det, double log_det_prior, double eps) {
  return HeatWeightOfLog(log_det, log_det_prior, std::log(eps));
}

double HeatWeightOfLog(double log_det, double log_det_prior, double log_eps) {
  const double above = log_det - log_eps;  // log(det Sigma / eps)
  const double prior_above = log_det_prior - log_eps;
  if (!(prior_above > 0.0)) return above > 0.0 ? 1.0 : 0.0;
  if (!(above > 0.0)) return 0.0;  // also catches NaN
  return std::min(1.0, above / prior_above);
}

Grid<float> MakeHeatmapGrid(const Vec2& size, double cell) {
  AIA_CHECK(cell > 0.0 && size.x() > 0.0 && size.y() > 0.0);
  // A hair below 1 keeps 20 / 0.1 from becoming 201 cells through rounding.
  const int nx = static_cast<int>(std::ceil(size.x() / cell - 1e-9));
  const int ny = static_cast<int>(std::ceil(size.y() / cell - 1e-9));
  return Grid<float>(nx, ny, cell, 0.0f);
}

namespace {

// The cut-off window of one Gaussian and its exponent's coefficients.
struct GaussianWindow {
  int x0 = 0, x1 = -1, y0 = 0, y1 = -1;  // cells, inclusive
  double pxx = 0.0, pyy = 0.0, pxy = 0.0, limit = 0.0;
};

GaussianWindow WindowOf(const Vec2& mu, const Mat2& sigma, double blur,
                        double cutoff, const Grid<float>& grid) {
  GaussianWindow g;
  const Mat2 s =
      0.5 * (sigma + sigma.transpose()) + blur * blur * Mat2::Identity();
  const double det = s.determinant();
  AIA_CHECK_MSG(det > 0.0, "heatmap covariance is not positive definite");
  // P = S^-1; the window is the ellipse's bounding box, |dx| <= cutoff
  // sqrt(S_xx).
  g.pxx = s(1, 1) / det;
  g.pyy = s(0, 0) / det;
  g.pxy = -s(0, 1) / det;
  const double cell = grid.cell();
  const double rx = cutoff * std::sqrt(s(0, 0)),
               ry = cutoff * std::sqrt(s(1, 1));
  g.limit = 0.5 * cutoff * cutoff;
  // Cells whose centres (i + 0.5) * cell lie in [mu - r, mu + r], clamped in
  // floating point first (a vague belief's window may exceed int's range).
  const auto first = [cell](double lo, int n) {
    return static_cast<int>(
        std::clamp(std::ceil(lo / cell - 0.5), 0.0, static_cast<double>(n)));
  };
  const auto last = [cell](double hi, int n) {
    return static_cast<int>(
        std::clamp(std::floor(hi / cell - 0.5), -1.0, n - 1.0));
  };
  g.x0 = first(mu.x() - rx, grid.nx());
  g.x1 = last(mu.x() + rx, grid.nx());
  g.y0 = first(mu.y() - ry, grid.ny());
  g.y1 = last(mu.y() + ry, grid.ny());
  return g;
}

// Calls f(row iy, ix, value) for each cell of the window inside the cut-off.
template <typename F>
void ForEachHeatCell(const Vec2& mu, const GaussianWindow& g, double weight,
                     double cell, F f) {
  for (int iy = g.y0; iy <= g.y1; ++iy) {
    const double dy = (iy + 0.5) * cell - mu.y();
    for (int ix = g.x0; ix <= g.x1; ++ix) {
      const double dx = (ix + 0.5) * cell - mu.x();
      const double q =
          0.5 * (g.pxx * dx * dx + 2.0 * g.pxy * dx * dy + g.pyy * dy * dy);
      if (q > g.limit) continue;
      f(iy, ix, static_cast<float>(weight * std::exp(-q)));
    }
  }
}

}  // namespace

void AddGaussianHeat(const Vec2& mu, const Mat2& sigma, double weight,
                     double blur, double cutoff, Grid<float>* out) {
  if (!(weight > 0.0)) return;
  const GaussianWindow g = WindowOf(mu, sigma, blur, cutoff, *out);
  float* data = out->data().data();
  const int nx = out->nx();
  ForEachHeatCell(mu, g, weight, out->cell(), [&](int iy, int ix, float v) {
    data[static_cast<size_t>(iy) * nx + ix] += v;
  });
}

void MakeHeatStamp(const Vec2& mu, const Mat2& sigma, double weight,
                   double blur, double cutoff, const Grid<float>& grid,
                   HeatStamp* out) {
  out->nx = out->ny = 0;
  out->values.clear();
  if (!(weight > 0.0)) return;
  const GaussianWindow g = WindowOf(mu, sigma, blur, cutoff, grid);
  if (g.x1 < g.x0 || g.y1 < g.y0) return;
  out->x0 = g.x0;
  out->y0 = g.y0;
  out->nx = g.x1 - g.x0 + 1;
  out->ny = g.y1 - g.y0 + 1;
  out->values.assign(static_cast<size_t>(out->nx) * out->ny, 0.0f);
  float* values = out->values.data();
  const int w = out->nx;
  ForEachHeatCell(mu, g, weight, grid.cell(), [&](int iy, int ix, float v) {
    values[static_cast<size_t>(iy - g.y0) * w + (ix - g.x0)] = v;
  });
}

void AddHeatStamp(const HeatStamp& stamp, bool subtract, Grid<float>* out) {
  float* data = out->data().data();
  const int nx = out->nx();
  const float* v = stamp.values.data();
  for (int y = 0; y < stamp.ny; ++y) {
    float* row = data + static_cast<size_t>(stamp.y0 + y) * nx + stamp.x0;
    const float* in = v + static_cast<size_t>(y) * stamp.nx;
    if (subtract) {
      for (int x = 0; x < stamp.nx; ++x) row[x] -= in[x];
    } else {
      for (int x = 0; x < stamp.nx; ++x) row[x] += in[x];
    }
  }
}

namespace {

// Adds target k's heat (nothing when it is localized).
void AddTargetHeat(const Vec2& mean, const Mat2& cov, double log_det,
                   double log_det_prior, const HeatmapParams& params,
                   Grid<float>* out) {
  const double w = HeatWeight(log_det, log_det_prior, params.eps);
  if (w > 0.0) AddGaussianHeat(mean, cov, w, params.blur, params.cutoff, out);
}

}  // namespace

void HeatSources(const BeliefSet& beliefs, int row,
                 std::vector<HeatSource>* out, const BeliefDigest* digest,
                 bool covariance) {
  const int m = beliefs.layout().num_targets();
  AIA_CHECK(row >= 0 && row < beliefs.rows());
  out->resize(m);
  for (int k = 0; k < m; ++k) {
    HeatSource& s = (*out)[k];
    s.mean = digest ? digest->Mean(row, k) : beliefs.PositionMean(row, k);
    if (covariance) s.cov = beliefs.PositionCovariance(row, k);
    s.log_det =
        digest ? digest->LogDet(row, k) : beliefs.LogDetCovariance(row, k);
  }
}

void ProjectHeatmap(const std::vector<HeatSource>& sources,
                    const std::vector<double>& log_det_prior,
                    const HeatmapParams& params, Grid<float>* out) {
  AIA_CHECK(log_det_prior.size() == sources.size());
  AIA_CHECK_MSG(out->nx() > 0 && out->ny() > 0,
                "size the heatmap grid first (MakeHeatmapGrid)");
  AIA_CHECK(params.eps > 0.0 && params.blur >= 0.0 && params.cutoff > 0.0);
  std::fill(out->data().begin(), out->data().end(), 0.0f);
  for (std::size_t k = 0; k < sources.size(); ++k)
    AddTargetHeat(sources[k].mean, sources[k].cov, sources[k].log_det,
                  log_det_prior[k], params, out);
}

void ProjectHeatmap(const BeliefSet& beliefs, int row,
                    const std::vector<double>& log_det_prior,
                    const HeatmapParams& params, Grid<float>* out) {
  const int m = beliefs.layout().num_targets();
  AIA_CHECK(row >= 0 && row < beliefs.rows());
  AIA_CHECK(static_cast<int>(log_det_prior.size()) == m);
  AIA_CHECK_MSG(out->nx() > 0 && out->ny() > 0,
                "size the heatmap grid first (MakeHeatmapGrid)");
  AIA_CHECK(params.eps > 0.0 && params.blur >= 0.0 && params.cutoff > 0.0);
  std::fill(out->data().begin(), out->data().end(), 0.0f);
  for (int k = 0; k < m; ++k)
    AddTargetHeat(
        beliefs.PositionMean(row, k), beliefs.PositionCovariance(row, k),
        beliefs.LogDetCovariance(row, k), log_det_prior[k], params, out);
}

namespace {

HeatSource SourceOf(const BeliefSet& beliefs, int row, int k) {
  HeatSource s;
  s.mean = beliefs.PositionMean(row, k);
  s.cov = beliefs.PositionCovariance(row, k);
  s.log_det = beliefs.LogDetCovariance(row, k);
  return s;
}

// A block rounded to 2^-40 of its scale (a power of two above max |Omega_ii|
// for Omega's entries, above max |xi_i| + that for xi's), as integers, the
// two scales' exponents last: blocks that agree this closely have the same key,
// and the key gives back one block for all of them (Dequantize).
constexpr int kKeyBits = 40;

// The exponent of a scale, with its steps at sqrt(2) times the powers of
// two: priors sit on powers of two (prior_sigma 1 gives Omega = I), and a
// step there would split one belief's rounded copies into two keys.
int ScaleExponent(double scale) {
  constexpr double kOffset = 0.70710678118654752;
  // 0 for a zero or non-finite scale: such a block keys as zeros (or
  // INT64_MIN), not as inf * 0.
  return scale > 0.0 && std::isfinite(scale) ? std::ilogb(scale * kOffset) + 2
                                             : 0;
}

void Quantize(const double* block, int d, std::int64_t* key) {
  double omega_scale = 0.0, xi_scale = 0.0;
  for (int i = 0; i < d; ++i)
    omega_scale = std::max(omega_scale, std::fabs(block[i * d + i]));
  for (int i = 0; i < d; ++i)
    xi_scale = std::max(xi_scale, std::fabs(block[d * d + i]));
  const int eo = ScaleExponent(omega_scale);
  const int ex = ScaleExponent(xi_scale + omega_scale);
  // Multiplying by a power of two is exact (as ldexp, but faster), and the
  // exponents stay far from the double range's ends.
  const double so = std::ldexp(1.0, kKeyBits - eo);
  const double sx = std::ldexp(1.0, kKeyBits - ex);
  for (int i = 0; i < d * d + d; ++i) {
    const double q = block[i] * (i < d * d ? so : sx);
    key[i] =
        std::isfinite(q) && std::fabs(q) < 9e18 ? std::llround(q) : INT64_MIN;
  }
  key[d * d + d] = eo;
  key[d * d + d + 1] = ex;
}

void Dequantize(const std::int64_t* key, int d, double* block) {
  const int eo = static_cast<int>(key[d * d + d]);
  const int ex = static_cast<int>(key[d * d + d + 1]);
  for (int i = 0; i < d * d + d; ++i)
    block[i] = std::ldexp(static_cast<double>(key[i]),
                          (i < d * d ? eo : ex) - kKeyBits);
}

// Each row's key of target k's block (dimension d), row b's at
// keys[b * (d * d + d + 2)]: a block equal bit for bit to the row before's
// has its key (common in a full graph, where most rows hold one belief).
void KeyRows(const BeliefSet& beliefs, const std::vector<int>& rows, int k,
             int d, std::int64_t* keys) {
  const int n = static_cast<int>(rows.size());
  const int len = d * d + d + 2;
  const std::size_t bytes = sizeof(double) * (d * d + d);
  const double* before = nullptr;
  for (int b = 0; b < n; ++b) {
    // (Rows that share the set's common block share its address.)
    const double* block = beliefs.Block(rows[b], k);
    if (before != nullptr &&
        (block == before || std::memcmp(block, before, bytes) == 0)) {
      std::copy(&keys[(b - 1) * len], &keys[b * len], &keys[b * len]);
    } else {
      Quantize(block, d, &keys[b * len]);
    }
    before = block;
  }
}

// Whether rows a and b have the same key (keys of `len` entries).
bool SameKey(const std::int64_t* keys, int len, int a, int b) {
  return std::equal(&keys[a * len], &keys[a * len] + len, &keys[b * len]);
}

// The row whose key more than half of the n rows have (Boyer-Moore's
// majority vote over the keys, then a count), or -1 where none does.
int MajorityRow(const std::int64_t* keys, int len, int n) {
  int candidate = -1, count = 0;
  for (int b = 0; b < n; ++b) {
    if (count == 0) {
      candidate = b;
      count = 1;
    } else {
      count += SameKey(keys, len, b, candidate) ? 1 : -1;
    }
  }
  if (candidate < 0) return -1;
  count = 0;
  for (int b = 0; b < n; ++b) count += SameKey(keys, len, b, candidate);
  return 2 * count > n ? candidate : -1;
}

}  // namespace

void TeamHeatmap::Prepare(const BeliefSet& beliefs,
                          const std::vector<int>& rows,
                          const std::vector<double>& log_det_prior,
                          const HeatmapParams& params, const Grid<float>& grid,
                          const RangeRunner& run, int workers) {
  const int m = beliefs.layout().num_targets();
  AIA_CHECK(static_cast<int>(log_det_prior.size()) == m);
  AIA_CHECK(params.eps > 0.0 && params.blur >= 0.0 && params.cutoff > 0.0);
  AIA_CHECK(workers >= 1);
  const RangeRunner serial = [](int n, const RangeTask& f) { f(0, n, 0); };
  const RangeRunner& runner = run ? run : serial;
  if (!run) workers = 1;
  common_.resize(m);
  ResetBase(grid);
  // The belief more than half the rows hold about each target, if any, to
  // 2^-40 of its scale. The majority's block is the one its key gives back,
  // so no robot's heatmap depends on the order of the rows: relabelling the
  // robots permutes them. Targets in parallel; their heat into the base in
  // order.
  const BeliefLayout& layout = beliefs.layout();
  const int n = static_cast<int>(rows.size());
  member_.assign(static_cast<std::size_t>(n) * m, 0);
  if (static_cast<int>(scratch_.size()) < workers) scratch_.resize(workers);
  runner(m, [&](int k0, int k1, int worker) {
    AIA_CHECK_MSG(worker >= 0 && worker < workers,
                  "a runner's worker index beyond `workers`");
    Scratch& w = scratch_[worker];
    // (Another layout may sit where an earlier one was: its stride too.)
    if (w.representative.rows() != 1 || &w.representative.layout() != &layout ||
        w.representative.data().cols() != layout.stride())
      w.representative = BeliefSet(&layout, 1);
    for (int k = k0; k < k1; ++k)
      CommonStamp(beliefs, rows, k, log_det_prior[k], params, grid, &w);
  });
  for (int k = 0; k < m; ++k) AddHeatStamp(common_[k], false, &base_);
  // Each row's own stamps where it holds another belief, rows in parallel.
  // Each row keeps its stamps' memory from step to step.
  if (robot_own_.size() < rows.size()) robot_own_.resize(rows.size());
  robot_used_.assign(rows.size(), 0);
  runner(n, [&](int b0, int b1, int) {
    for (int b = b0; b < b1; ++b)
      robot_used_[b] =
          OwnStamps(beliefs, rows[b], b, log_det_prior, params, grid);
  });
  own_used_ = 0;
  for (const int u : robot_used_) own_used_ += u;
}

void TeamHeatmap::ResetBase(const Grid<float>& grid) {
  if (base_.nx() != grid.nx() || base_.ny() != grid.ny() ||
      base_.cell() != grid.cell()) {
    base_ = Grid<float>(grid.nx(), grid.ny(), grid.cell(), 0.0f);
  } else {
    std::fill(base_.data().begin(), base_.data().end(), 0.0f);
  }
}

void TeamHeatmap::CommonStamp(const BeliefSet& beliefs,
                              const std::vector<int>& rows, int k,
                              double log_det_prior, const HeatmapParams& params,
                              const Grid<float>& grid, Scratch* w) {
  const int m = static_cast<int>(common_.size());
  const int n = static_cast<int>(rows.size());
  const int d = beliefs.layout().dim(k);
  const int len = d * d + d + 2;
  w->keys.resize(static_cast<std::size_t>(n) * len);
  std::int64_t* keys = w->keys.data();
  KeyRows(beliefs, rows, k, d, keys);
  HeatStamp& stamp = common_[k];
  stamp.nx = stamp.ny = 0;
  const int majority = MajorityRow(keys, len, n);
  if (majority < 0) return;
  for (int b = 0; b < n; ++b)
    member_[static_cast<std::size_t>(b) * m + k] =
        SameKey(keys, len, b, majority);
  Dequantize(&keys[majority * len], d, w->representative.Omega(0, k).data());
  const HeatSource s = SourceOf(w->representative, 0, k);
  MakeHeatStamp(s.mean, s.cov, HeatWeight(s.log_det, log_det_prior, params.eps),
                params.blur, params.cutoff, grid, &stamp);
}

int TeamHeatmap::OwnStamps(const BeliefSet& beliefs, int row, int b,
                           const std::vector<double>& log_det_prior,
                           const HeatmapParams& params,
                           const Grid<float>& grid) {
  const int m = static_cast<int>(common_.size());
  std::vector<Own>& own = robot_own_[b];
  int used = 0;
  for (int k = 0; k < m; ++k) {
    if (member_[static_cast<std::size_t>(b) * m + k]) continue;
    const HeatSource s = SourceOf(beliefs, row, k);
    const double w = HeatWeight(s.log_det, log_det_prior[k], params.eps);
    if (!(w > 0.0) && common_[k].nx == 0) continue;  // no heat either way
    if (used == static_cast<int>(own.size())) own.emplace_back();
    own[used].target = k;
    MakeHeatStamp(s.mean, s.cov, w, params.blur, params.cutoff, grid,
                  &own[used].stamp);
    ++used;
  }
  return used;
}

void TeamHeatmap::Edits(int b, std::vector<HeatEdit>* out) const {
  AIA_CHECK(b >= 0 && b < static_cast<int>(robot_used_.size()));
  out->clear();
  for (int o = 0; o < robot_used_[b]; ++o) {
    const Own& own = robot_own_[b][o];
    out->push_back({&common_[own.target], true});
    out->push_back({&own.stamp, false});
  }
}

const Grid<float>& TeamHeatmap::Robot(int b, Grid<float>* scratch) const {
  AIA_CHECK(b >= 0 && b < static_cast<int>(robot_used_.size()));
  if (robot_used_[b] == 0) return base_;
  Grid<float>* out = scratch;
  AIA_CHECK(out->nx() == base_.nx() && out->ny() == base_.ny());
  std::copy(base_.data().begin(), base_.data().end(), out->data().begin());
  for (int o = 0; o < robot_used_[b]; ++o) {
    const Own& own = robot_own_[b][o];
    AddHeatStamp(common_[own.target], true, out);
    AddHeatStamp(own.stamp, false, out);
  }
  return *out;
}

const Grid<float>& TeamHeatmap::Robot(int b,
                                      const std::vector<std::uint8_t>& keep,
                                      Grid<float>* scratch) const {
  AIA_CHECK(b >= 0 && b < static_cast<int>(robot_used_.size()));
  const int m = static_cast<int>(common_.size());
  AIA_CHECK(static_cast<int>(keep.size()) == m);
  Grid<float>* out = scratch;
  AIA_CHECK(out->nx() == base_.nx() && out->ny() == base_.ny());
  std::fill(out->data().begin(), out->data().end(), 0.0f);
  for (int k = 0; k < m; ++k)
    if (keep[k] && member_[static_cast<std::size_t>(b) * m + k])
      AddHeatStamp(common_[k], false, out);
  for (int o = 0; o < robot_used_[b]; ++o) {
    const Own& own = robot_own_[b][o];
    if (keep[own.target]) AddHeatStamp(own.stamp, false, out);
  }
  return *out;
}

}  // namespace aia
