#include "aia/estimation/heatmap.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "aia/core/check.h"

namespace aia {

double HeatWeight(double log_det, double log_det_prior, double eps) {
  const double log_eps = std::log(eps);
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

void AddGaussianHeat(const Vec2& mu, const Mat2& sigma, double weight,
                     double blur, double cutoff, Grid<float>* out) {
  if (!(weight > 0.0)) return;
  const Mat2 s =
      0.5 * (sigma + sigma.transpose()) + blur * blur * Mat2::Identity();
  const double det = s.determinant();
  AIA_CHECK_MSG(det > 0.0, "heatmap covariance is not positive definite");
  // P = S^-1; the window is the ellipse's bounding box, |dx| <= cutoff
  // sqrt(S_xx).
  const double pxx = s(1, 1) / det, pyy = s(0, 0) / det, pxy = -s(0, 1) / det;
  const double cell = out->cell();
  const double rx = cutoff * std::sqrt(s(0, 0)),
               ry = cutoff * std::sqrt(s(1, 1));
  const double limit = 0.5 * cutoff * cutoff;
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
  const int x0 = first(mu.x() - rx, out->nx()),
            x1 = last(mu.x() + rx, out->nx());
  const int y0 = first(mu.y() - ry, out->ny()),
            y1 = last(mu.y() + ry, out->ny());
  float* data = out->data().data();
  for (int iy = y0; iy <= y1; ++iy) {
    const double dy = (iy + 0.5) * cell - mu.y();
    float* row = data + out->Index(0, iy);
    for (int ix = x0; ix <= x1; ++ix) {
      const double dx = (ix + 0.5) * cell - mu.x();
      const double q =
          0.5 * (pxx * dx * dx + 2.0 * pxy * dx * dy + pyy * dy * dy);
      if (q > limit) continue;
      row[ix] += static_cast<float>(weight * std::exp(-q));
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
                 std::vector<HeatSource>* out) {
  const int m = beliefs.layout().num_targets();
  AIA_CHECK(row >= 0 && row < beliefs.rows());
  out->resize(m);
  for (int k = 0; k < m; ++k) {
    HeatSource& s = (*out)[k];
    s.mean = beliefs.PositionMean(row, k);
    s.cov = beliefs.PositionCovariance(row, k);
    s.log_det = beliefs.LogDetCovariance(row, k);
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

}  // namespace aia
