#include "aia/learning/channels.h"

#include <algorithm>
#include <cmath>

#include "aia/core/check.h"

namespace aia {

std::string_view ChannelFrameName(ChannelFrame frame) {
  return frame == ChannelFrame::kGlobal ? "global" : "centred";
}

bool ParseChannelFrame(std::string_view text, ChannelFrame* frame) {
  if (text == "global") {
    *frame = ChannelFrame::kGlobal;
  } else if (text == "centred" || text == "centered") {
    *frame = ChannelFrame::kCentred;
  } else {
    return false;
  }
  return true;
}

ChannelRenderer::ChannelRenderer(const Grid<std::uint8_t>& occupancy,
                                 const Vec2& size, const ChannelParams& params)
    : params_(params), size_(size) {
  AIA_CHECK(params.cell > 0.0 && params.window > 0 && params.blur >= 0.0 &&
            params.cutoff > 0.0);
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
  if (params.frame == ChannelFrame::kGlobal) {
    height_ = occupancy_.ny();
    width_ = occupancy_.nx();
  } else {
    height_ = width_ = params.window;
  }
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
                             double eps, float* out) {
  ProjectHeatmap(targets, log_det_prior, Heatmap(eps), &heat_);
  RenderWithHeat(self, neighbours, heat_, out);
}

void ChannelRenderer::RenderWithHeat(const Vec2& self,
                                     const std::vector<Vec2>& neighbours,
                                     const Grid<float>& field,
                                     float* out) const {
  AIA_CHECK(field.nx() == occupancy_.nx() && field.ny() == occupancy_.ny());
  const std::size_t plane = static_cast<std::size_t>(height_) * width_;
  float* occ = out;
  float* own = out + plane;
  float* nbr = out + 2 * plane;
  float* heat = out + 3 * plane;
  std::fill(out, out + kNumChannels * plane, 0.0f);
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
  // Row by row: the cells left of the window fold onto its first column,
  // those right of it onto its last, the rest onto their own column.
  const int mid0 = std::clamp(x0, 0, nx), mid1 = std::clamp(x0 + w, 0, nx);
  for (int gy = 0; gy < ny; ++gy) {
    float* h = heat + fold(gy, y0) * w;
    const float* row = field.data().data() + field.Index(0, gy);
    float left = 0.0f, right = 0.0f;
    for (int gx = 0; gx < mid0; ++gx) left = std::max(left, row[gx]);
    for (int gx = mid1; gx < nx; ++gx) right = std::max(right, row[gx]);
    h[0] = std::max(h[0], left);
    h[w - 1] = std::max(h[w - 1], right);
    for (int gx = mid0; gx < mid1; ++gx)
      h[gx - x0] = std::max(h[gx - x0], row[gx]);
  }
}

}  // namespace aia
