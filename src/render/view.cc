#include "aia/render/view.h"

#include <algorithm>
#include <cmath>

#include "aia/core/check.h"

namespace aia {

TopDownView::TopDownView(const Vec2& size, int width, int height,
                         double fovy_deg, int band_px, double top_z,
                         double margin)
    : width_(width), height_(height), band_px_(band_px) {
  AIA_CHECK(width > 0 && height > 0 && band_px >= 0 && band_px < height);
  AIA_CHECK(fovy_deg > 0.0 && fovy_deg < 180.0);
  constexpr double kPi = 3.14159265358979323846;
  focal_ = 0.5 * height / std::tan(0.5 * fovy_deg * kPi / 180.0);
  // The framed rectangle at height top_z must fit in half the free pixels on
  // each side of its centre: f (half + margin) / (h - top_z) <= free / 2.
  const double half_x = 0.5 * size.x() + margin,
               half_y = 0.5 * size.y() + margin;
  const double free_x = 0.5 * width, free_y = 0.5 * (height - band_px);
  height_m_ = top_z + focal_ * std::max(half_x / free_x, half_y / free_y);
  // The workspace centre sits in the middle of the free part of the image,
  // band_px / 2 below the image centre, so the lookat point is above it.
  const double floor_scale = focal_ / height_m_;
  center_ = 0.5 * size + Vec2(0.0, 0.5 * band_px / floor_scale);
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
