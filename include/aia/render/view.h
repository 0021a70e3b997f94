// The fixed top-down view of a mission video and its exact world -> pixel map.
// MuJoCo 2.2 has no orthographic camera, so the view is a perspective free
// camera looking straight down from height h above the workspace. For such a
// camera a point at height z maps by a pure scale and offset:
//   u = W/2 + f (X - X0) / (h - z),   v = H/2 - f (Y - Y0) / (h - z),
// with f = (H/2) / tan(fovy/2) pixels (mjr_render widens the frustum to the
// viewport's aspect, so pixels are square). Overlays drawn with this map land
// on the rendered scene to a fraction of a pixel (tests/render/view_test.cc).
// The workspace is framed in the image less a band at the top (the heads-up
// line) and a column at the right (the legend), so neither covers it.
#ifndef AIA_RENDER_VIEW_H_
#define AIA_RENDER_VIEW_H_

#include <mujoco/mujoco.h>

#include "aia/core/types.h"

namespace aia {

class TopDownView {
 public:
  // Frames the workspace [0, size.x] x [0, size.y] (its border walls and the
  // tops of obstacles `top_z` high included, plus `margin` metres) in a
  // width x height image, below a band of `band_px` pixels kept free at the
  // top for the heads-up line and left of a column of `side_px` pixels kept
  // free at the right for the legend: h is the smallest camera height at
  // which the rectangle at height top_z lies within the free pixels
  // [0, width - side_px] x [band_px, height], and the floor's centre maps to
  // the centre of those pixels. `fovy_deg` is the model's vertical field of
  // view (<visual><global fovy>).
  TopDownView(const Vec2& size, int width, int height, double fovy_deg,
              int band_px, double top_z = 0.5, double margin = 0.25,
              int side_px = 0);

  // The MuJoCo free camera that renders this view.
  void SetCamera(mjvCamera* camera) const;

  // Pixel coordinates of a world point at height z, continuous, with (0, 0)
  // the top-left corner of the top-left pixel (pixel (c, r) covers
  // [c, c+1) x [r, r+1)); OpenCV's drawing functions put pixel centres at
  // integers, so subtract 0.5 before drawing.
  Vec2 ToPixel(const Vec2& p, double z = 0.0) const {
    const double s = focal_ / (height_m_ - z);
    return {0.5 * width_ + s * (p.x() - center_.x()),
            0.5 * height_ - s * (p.y() - center_.y())};
  }
  // Pixels per metre at height z.
  double Scale(double z = 0.0) const { return focal_ / (height_m_ - z); }

  int width() const { return width_; }
  int height() const { return height_; }
  int band_px() const { return band_px_; }
  int side_px() const { return side_px_; }
  double focal() const { return focal_; }             // f, pixels
  double camera_height() const { return height_m_; }  // h, metres
  const Vec2& center() const { return center_; }  // (X0, Y0), the lookat point

 private:
  int width_, height_, band_px_, side_px_;
  double focal_ = 1.0;
  double height_m_ = 1.0;
  Vec2 center_{0.0, 0.0};
};

}  // namespace aia

#endif  // AIA_RENDER_VIEW_H_
