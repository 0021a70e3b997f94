#include "aia/render/view.h"

#include <algorithm>
#include <cmath>

#include "aia/core/check.h"

namespace aia {
namespace {

// The smallest camera height h at which [c - half, c + half] at height top_z
// projects into the free pixels [lo, hi] along one image axis whose optical
// centre (the principal point) is `axis`, when the floor's centre c maps to
// (lo + hi) / 2. A point at height z maps to axis + f (X - X0) / (h - z) with
// X0 chosen so that c lands mid-way (X0 = c - ((lo + hi) / 2 - axis) h / f);
// the rectangle's edges then land at
//   axis + (h ((lo + hi) / 2 - axis) +- f half) / (h - top_z),
// and both lie within [lo, hi] exactly when
//   h (hi - lo) / 2 >= f half + top_z max(axis - lo, hi - axis).
double FitHeight(double focal, double half, double top_z, double lo, double hi,
                 double axis) {
  const double room = 0.5 * (hi - lo);
  return (focal * half + top_z * std::max(axis - lo, hi - axis)) / room;
}

}  // namespace

TopDownView::TopDownView(const Vec2& size, int width, int height,
                         double fovy_deg, int band_px, double top_z,
                         double margin, int side_px)
    : width_(width), height_(height), band_px_(band_px), side_px_(side_px) {
  AIA_CHECK(width > 0 && height > 0 && band_px >= 0 && band_px < height);
  AIA_CHECK(side_px >= 0 && side_px < width);
  AIA_CHECK(fovy_deg > 0.0 && fovy_deg < 180.0);
  AIA_CHECK(top_z >= 0.0);
  focal_ = 0.5 * height / std::tan(0.5 * fovy_deg * kPi / 180.0);
  const double half_x = 0.5 * size.x() + margin,
               half_y = 0.5 * size.y() + margin;
  // Image rows grow downwards, so the y axis is the rows mirrored: the same
  // fit with the free rows [band_px, height] about the centre row.
  height_m_ = std::max(
      {FitHeight(focal_, half_x, top_z, 0.0, width - side_px, 0.5 * width),
       FitHeight(focal_, half_y, top_z, band_px, height, 0.5 * height),
       top_z + 1e-6});
  // The workspace centre sits in the middle of the free pixels: side_px / 2
  // left of and band_px / 2 below the image centre, so the lookat point is
  // right of and above it.
  const double floor_scale = focal_ / height_m_;
  center_ = 0.5 * size + Vec2(0.5 * side_px, 0.5 * band_px) / floor_scale;
}

void TopDownView::SetCamera(mjvCamera* camera) const {
  mjv_defaultCamera(camera);
  camera->type = mjCAMERA_FREE;
  // Looking down -z with +y up in the image and +x to the right.
  camera->elevation = -90.0;
  camera->azimuth = 90.0;
  camera->lookat[0] = center_.x();
  camera->lookat[1] = center_.y();
  camera->lookat[2] = 0.0;
  camera->distance = height_m_;
}

}  // namespace aia
