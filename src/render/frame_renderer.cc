#include "aia/render/frame_renderer.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "aia/core/check.h"
#include "aia/core/clock.h"
#include "aia/world/mjcf.h"

namespace aia {
namespace {

// OpenCV draws in fixed point with kShift fractional bits: sub-pixel overlays.
constexpr int kShift = 4;
constexpr double kOne = 1 << kShift;

// Continuous pixel coordinates (TopDownView) -> OpenCV fixed point, whose
// integer points are pixel centres.
// Clamped far outside any image, so that a wild estimate cannot overflow.
cv::Point Fixed(const Vec2& px) {
  constexpr double kFar = 1e6;
  return {cvRound((std::clamp(px.x(), -kFar, kFar) - 0.5) * kOne),
          cvRound((std::clamp(px.y(), -kFar, kFar) - 0.5) * kOne)};
}
int FixedLength(double pixels) { return cvRound(pixels * kOne); }

cv::Scalar RobotBgr(int robot, double shade = 1.0) {
  const std::array<float, 3> c = RobotColor(robot);
  return {255.0 * shade * c[2], 255.0 * shade * c[1], 255.0 * shade * c[0]};
}

const cv::Scalar kLocalized(40, 160, 40);    // green: det Sigma <= eps
const cv::Scalar kUnlocalized(30, 30, 215);  // red: prior-sized uncertainty
const cv::Scalar kNearly(0, 150, 250);       // orange: just above eps
const cv::Scalar kEdge(150, 90, 40);         // delivered message
const cv::Scalar kLost(0, 0, 230);           // lost message
const cv::Scalar kFailed(90, 90, 90);
const cv::Scalar kBlack(20, 20, 20);

// Above eps the colour runs from orange (w ~ 0) to red (w = 1).
cv::Scalar TargetColor(const TargetOverlay& t, double eps) {
  if (t.det <= eps) return kLocalized;
  const double w = std::clamp(t.weight, 0.0, 1.0);
  return kNearly * (1.0 - w) + kUnlocalized * w;
}

void DashedLine(cv::Mat* image, const Vec2& a, const Vec2& b,
                const cv::Scalar& color, int thickness, double dash,
                double gap) {
  const Vec2 d = b - a;
  const double length = d.norm();
  if (length < 1e-9) return;
  const Vec2 u = d / length;
  for (double s = 0.0; s < length; s += dash + gap) {
    const double e = std::min(length, s + dash);
    cv::line(*image, Fixed(a + s * u), Fixed(a + e * u), color, thickness,
             cv::LINE_AA, kShift);
  }
}

// A compact target: a square of half-size `half` pixels around `center`
// (continuous pixel coordinates) in `color`, so that it differs from the
// robots' round dots; outlined dark unless `outline` is 0 (a localized
// target, which needs no more attention).
void DrawTargetMarker(cv::Mat* image, const Vec2& center, double half,
                      const cv::Scalar& color, int outline) {
  const cv::Point corners[4] = {
      Fixed(center + Vec2(-half, -half)), Fixed(center + Vec2(half, -half)),
      Fixed(center + Vec2(half, half)), Fixed(center + Vec2(-half, half))};
  cv::fillConvexPoly(*image, corners, 4, color, cv::LINE_AA, kShift);
  if (outline <= 0) return;
  const cv::Point* polygon = corners;
  const int count = 4;
  cv::polylines(*image, &polygon, &count, 1, true, kBlack, outline, cv::LINE_AA,
                kShift);
}

// An X of half-width `arm` (fixed point) through `p`: a target's mean, a
// failed robot.
void DrawCross(cv::Mat* image, const cv::Point& p, int arm,
               const cv::Scalar& color, int thickness) {
  cv::line(*image, p + cv::Point(-arm, -arm), p + cv::Point(arm, arm), color,
           thickness, cv::LINE_AA, kShift);
  cv::line(*image, p + cv::Point(-arm, arm), p + cv::Point(arm, -arm), color,
           thickness, cv::LINE_AA, kShift);
}

// A failed robot: a grey disc of radius `radius`, crossed (fixed point).
void DrawFailedRobot(cv::Mat* image, const cv::Point& p, int radius, int arm,
                     int thickness) {
  cv::circle(*image, p, radius, kFailed, cv::FILLED, cv::LINE_AA, kShift);
  DrawCross(image, p, arm, kFailed, thickness);
}

// A target's 2-sigma ellipse with axes (a, b) in fixed point.
void DrawEllipse(cv::Mat* image, const cv::Point& p, int a, int b, double angle,
                 const cv::Scalar& color, int thickness) {
  cv::ellipse(*image, p, cv::Size(a, b), angle, 0.0, 360.0, color, thickness,
              cv::LINE_AA, kShift);
}

// The legend's column: 140 pixels at 480 rows, growing with the image.
constexpr double kLegendColumn = 140.0;
// The column is kept only when it shrinks the workspace by at most this much
// (never for a square workspace in a 4:3 or wider image).
constexpr double kLegendMaxLoss = 0.15;
// MuJoCo's robot discs and target spheres are drawn (as bodies of the scene)
// only while a robot's disc is at least this many pixels in radius and there
// are at most kMaxSceneBodies robots and targets; else the overlay draws dots.
constexpr double kMinBodyPixels = 2.0;
constexpr int kMaxSceneBodies = 250;
// Trails: robot-steps in all, and the fewest per robot.
constexpr int kTrailBudget = 500;
constexpr int kMinTrail = 5;
// Border walls' thickness outside the workspace (world/mjcf.cc).
constexpr double kWallThickness = 0.1;

const cv::Scalar kPaper(236, 236, 236);      // the legend's background
const cv::Scalar kTint(120, 215, 250);       // sensing discs as one tint
const cv::Scalar kLegendOff(200, 200, 200);  // a legend row for what is off
// MuJoCo's target spheres (world/mjcf.h), in BGR.
const cv::Scalar kTargetBgr(255.0 * kTargetRgb[2], 255.0 * kTargetRgb[1],
                            255.0 * kTargetRgb[0]);
constexpr double kDiscAlpha = 0.18, kTintAlpha = 0.22;

double Unit(int image_height) { return std::max(1.0, image_height / 480.0); }

struct LegendGeometry {
  int row = 0, icon = 0, pad = 0;
};
LegendGeometry LegendRows(int image_height) {
  const double unit = Unit(image_height);
  LegendGeometry g;
  g.row = std::max(12, static_cast<int>(std::lround(18 * unit)));
  g.icon = static_cast<int>(std::lround(1.3 * g.row));
  g.pad = std::max(3, g.row / 4);
  return g;
}
constexpr int kMaxLegendRows = 9;

// The view of a frame: the workspace below the heads-up band and, when the
// image is wide enough, left of the legend's column.
TopDownView FrameView(const Vec2& size, const SceneSettings& s, double fovy) {
  const int band = HudBandPixels(s.height);
  const TopDownView plain(size, s.width, s.height, fovy, band, kObstacleHeight);
  const int column =
      static_cast<int>(std::lround(kLegendColumn * Unit(s.height)));
  const LegendGeometry g = LegendRows(s.height);
  if (column >= s.width / 2 ||
      kMaxLegendRows * g.row + 2 * g.pad > s.height - band - 2 * g.pad)
    return plain;
  const TopDownView beside(size, s.width, s.height, fovy, band, kObstacleHeight,
                           0.25, column);
  return beside.Scale() >= (1.0 - kLegendMaxLoss) * plain.Scale() ? beside
                                                                  : plain;
}

}  // namespace

int HudBandPixels(int image_height) {
  return std::max(12, static_cast<int>(std::lround(0.055 * image_height)));
}

int TrailSteps(int trail_steps, int robots) {
  if (trail_steps <= 0) return 0;
  return std::min(trail_steps,
                  std::max(kMinTrail, kTrailBudget / std::max(1, robots)));
}

FrameRenderer::FrameRenderer(const Simulation& sim, const Map& map,
                             const FrameSettings& settings)
    : sim_(sim),
      settings_(settings),
      scene_(sim.model(), settings.scene),
      view_(
          FrameView(map.size(), settings.scene, sim.model()->vis.global.fovy)),
      robot_radius_(map.robot_radius()),
      world_area_m2_(map.size().x() * map.size().y()),
      trail_steps_(TrailSteps(settings.trail_steps, sim.num_robots())),
      trails_(sim.num_robots()) {
  const Vec2& size = map.size();
  const int width = settings.scene.width, height = settings.scene.height;
  view_.SetCamera(&camera_);
  const cv::Rect image(0, 0, width, height);
  // The workspace's floor rectangle in whole pixels, for the heatmap layer.
  const Vec2 top_left = view_.ToPixel({0.0, size.y()});
  const Vec2 bottom_right = view_.ToPixel({size.x(), 0.0});
  const int x0 = static_cast<int>(std::lround(top_left.x()));
  const int y0 = static_cast<int>(std::lround(top_left.y()));
  const int x1 = static_cast<int>(std::lround(bottom_right.x()));
  const int y1 = static_cast<int>(std::lround(bottom_right.y()));
  heat_rect_ =
      cv::Rect(x0, y0, std::max(1, x1 - x0), std::max(1, y1 - y0)) & image;
  // The walls' tops, in the pixels that they touch.
  const double t = kWallThickness;
  const Vec2 wall_tl = view_.ToPixel({-t, size.y() + t}, kObstacleHeight);
  const Vec2 wall_br = view_.ToPixel({size.x() + t, -t}, kObstacleHeight);
  const int wx0 = static_cast<int>(std::floor(wall_tl.x()));
  const int wy0 = static_cast<int>(std::floor(wall_tl.y()));
  world_rect_ =
      cv::Rect(wx0, wy0, static_cast<int>(std::ceil(wall_br.x())) - wx0,
               static_cast<int>(std::ceil(wall_br.y())) - wy0) &
      image;
  // The legend: in the view's column, just right of the walls.
  if (view_.side_px() > 0) {
    const int pad = LegendRows(height).pad;
    const int left =
        std::min(world_rect_.br().x + 2 * pad, width - view_.side_px() + pad);
    legend_room_ =
        cv::Rect(left, view_.band_px() + pad, view_.side_px() - 2 * pad,
                 height - view_.band_px() - 2 * pad);
  }
  // Bodies too small or too many to show: MuJoCo draws the static world
  // (floor, walls, obstacles) once, the overlay the robots and targets.
  const double robot_px = robot_radius_ * view_.Scale(2 * kRobotHalfHeight);
  compact_ = robot_px < kMinBodyPixels ||
             sim.num_robots() + sim.num_targets() > kMaxSceneBodies;
  if (compact_) scene_.SetGroupVisible(kGroupAgent, false);
  wheeled_ = sim.robot_model() == RobotModel::kDiffDrive;
  legend_key_.messages =
      settings_.edges == EdgeMode::kAll || settings_.edges == EdgeMode::kAuto;
  legend_key_.lost = settings_.edges != EdgeMode::kNone;
  BuildLegend(legend_key_);
}

std::vector<std::pair<FrameRenderer::LegendIcon, const char*>>
FrameRenderer::LegendRowsFor(const LegendKey& key) const {
  std::vector<std::pair<LegendIcon, const char*>> rows = {
      {LegendIcon::kRobot, wheeled_ ? "robot, heading" : "robot"},
      {LegendIcon::kSensing, key.tint ? "sensed area" : "sensing range"},
      {LegendIcon::kMessage, key.messages ? "message" : "message: off"},
      {LegendIcon::kLost, key.lost ? "lost message" : "lost: off"}};
  // Compact: the target is the marker coloured by det Sigma.
  if (!compact_) rows.push_back({LegendIcon::kTarget, "target"});
  rows.push_back(
      {LegendIcon::kUncertain, compact_ ? "target, det > eps" : "det > eps"});
  rows.push_back(
      {LegendIcon::kLocalized, compact_ ? "target, det <= eps" : "det <= eps"});
  rows.push_back({LegendIcon::kFailed, "failed robot"});
  if (key.heat) rows.push_back({LegendIcon::kHeat, "heat"});
  return rows;
}

void FrameRenderer::DrawLegendIcon(LegendIcon icon, double cy,
                                   const LegendKey& key) {
  const double unit = Unit(view_.height());
  const int thin = static_cast<int>(std::lround(unit));
  const int thick = static_cast<int>(std::lround(2 * unit));
  const LegendGeometry g = LegendRows(view_.height());
  const int row = g.row, pad = g.pad;
  const double cx = pad + 0.5 * g.icon;
  const Vec2 c(cx + 0.5, cy + 0.5);  // continuous coordinates of the centre
  const cv::Point p = Fixed(c);
  const double r = 0.36 * row;
  const Vec2 left(pad + 0.5, cy + 0.5), right(pad + g.icon + 0.5, cy + 0.5);
  switch (icon) {
    case LegendIcon::kRobot:
      cv::circle(legend_, p, FixedLength(0.22 * row), RobotBgr(0), cv::FILLED,
                 cv::LINE_AA, kShift);
      cv::circle(legend_, p, FixedLength(0.22 * row), kBlack, thin, cv::LINE_AA,
                 kShift);
      // The overlay's heading hand, facing up.
      if (wheeled_)
        cv::line(legend_, p, Fixed(c - Vec2(0.0, 0.36 * row)), kBlack, thick,
                 cv::LINE_AA, kShift);
      break;
    case LegendIcon::kSensing:
      if (key.tint) {
        cv::circle(legend_, p, FixedLength(r),
                   kTint * kTintAlpha + kPaper * (1.0 - kTintAlpha), cv::FILLED,
                   cv::LINE_AA, kShift);
        break;
      }
      cv::circle(legend_, p, FixedLength(r), RobotBgr(3) * 0.25 + kPaper * 0.75,
                 cv::FILLED, cv::LINE_AA, kShift);
      cv::circle(legend_, p, FixedLength(r), RobotBgr(3, 0.8), thin,
                 cv::LINE_AA, kShift);
      break;
    case LegendIcon::kMessage:
      cv::line(legend_, Fixed(left), Fixed(right),
               key.messages ? kEdge : kLegendOff, thin, cv::LINE_AA, kShift);
      break;
    case LegendIcon::kLost:
      DashedLine(&legend_, left, right, key.lost ? kLost : kLegendOff, thin,
                 5 * unit, 4 * unit);
      break;
    case LegendIcon::kTarget:
      cv::circle(legend_, p, FixedLength(0.12 * row), kTargetBgr, cv::FILLED,
                 cv::LINE_AA, kShift);
      cv::circle(legend_, p, FixedLength(0.26 * row), kBlack, thin, cv::LINE_AA,
                 kShift);
      break;
    case LegendIcon::kUncertain:
    case LegendIcon::kLocalized: {
      const cv::Scalar color =
          icon == LegendIcon::kUncertain ? kUnlocalized : kLocalized;
      const int a = FixedLength(0.46 * g.icon), b = FixedLength(r);
      if (compact_) {
        DrawEllipse(&legend_, p, a, b, 0.0, color, thin);
        DrawTargetMarker(&legend_, c, 0.16 * row, color,
                         icon == LegendIcon::kUncertain ? thin : 0);
        break;
      }
      DrawEllipse(&legend_, p, a, b, 0.0, color, thick);
      DrawCross(&legend_, p, FixedLength(0.12 * row), color, thick);
      break;
    }
    case LegendIcon::kFailed:
      DrawFailedRobot(&legend_, p, FixedLength(0.2 * row),
                      FixedLength(0.3 * row), thick);
      break;
    case LegendIcon::kHeat: {
      // The heat scale, H from 0 (left) to 1, as DrawHeatmap blends it.
      const int x0 = pad, w = g.icon, y0 = static_cast<int>(cy - 0.3 * row);
      const int h = std::max(2, static_cast<int>(0.6 * row));
      cv::Mat value(1, w, CV_8U), shade, color;
      for (int x = 0; x < w; ++x)
        value.at<unsigned char>(0, x) =
            static_cast<unsigned char>(255 * x / std::max(1, w - 1));
      value.convertTo(shade, CV_8U, 0.55, 0.2 * 255.0);
      cv::applyColorMap(shade, color, cv::COLORMAP_INFERNO);
      for (int x = 0; x < w; ++x) {
        const double a =
            settings_.heat_alpha * value.at<unsigned char>(0, x) / 255.0;
        const cv::Vec3b c3 = color.at<cv::Vec3b>(0, x);
        const cv::Scalar blended(a * c3[0] + (1 - a) * kPaper[0],
                                 a * c3[1] + (1 - a) * kPaper[1],
                                 a * c3[2] + (1 - a) * kPaper[2]);
        cv::line(legend_, {x0 + x, y0}, {x0 + x, y0 + h - 1}, blended, 1);
      }
      break;
    }
  }
}

void FrameRenderer::BuildLegend(const LegendKey& key) {
  legend_key_ = key;
  legend_built_ = true;
  if (legend_room_.empty()) return;
  legend_rect_ = legend_room_;
  const LegendGeometry g = LegendRows(view_.height());
  const int row = g.row, icon = g.icon, pad = g.pad;
  const std::vector<std::pair<LegendIcon, const char*>> rows =
      LegendRowsFor(key);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  const int text_room = legend_rect_.width - icon - 3 * pad;
  double scale = row / 42.0;
  int baseline = 0;
  for (const auto& [what, label] : rows) {
    const cv::Size size = cv::getTextSize(label, font, scale, 1, &baseline);
    if (size.width > text_room)
      scale *= static_cast<double>(text_room) / size.width;
  }
  const int height = std::min(legend_room_.height,
                              static_cast<int>(rows.size()) * row + 2 * pad);
  legend_rect_.height = height;
  legend_.create(height, legend_rect_.width, CV_8UC3);
  legend_.setTo(kPaper);
  cv::rectangle(legend_, cv::Rect(0, 0, legend_.cols, legend_.rows),
                cv::Scalar(150, 150, 150), 1);
  for (size_t i = 0; i < rows.size(); ++i) {
    const double cy = pad + (i + 0.5) * row;
    DrawLegendIcon(rows[i].first, cy, key);
    const char* label = rows[i].second;
    const cv::Size size = cv::getTextSize(label, font, scale, 1, &baseline);
    cv::putText(
        legend_, label,
        cv::Point(pad * 2 + icon, static_cast<int>(cy + 0.5 * size.height)),
        font, scale, cv::Scalar(40, 40, 40), 1, cv::LINE_AA);
  }
}

void FrameRenderer::AddTrailPoints(const std::vector<Vec2>& robots) {
  AIA_CHECK(robots.size() == trails_.size());
  for (size_t i = 0; i < robots.size(); ++i) {
    std::deque<Vec2>& trail = trails_[i];
    if (!trail.empty() && (trail.back() - robots[i]).squaredNorm() < 1e-8)
      continue;
    trail.push_back(robots[i]);
    if (trail_steps_ > 0)
      while (static_cast<int>(trail.size()) > trail_steps_ + 1)
        trail.pop_front();
  }
}

void FrameRenderer::SetHeatmap(const Grid<float>* heat) {
  if (heat == nullptr || heat_rect_.empty()) {
    heat_bgr_.release();
    heat_alpha_.release();
    return;
  }
  // Grid row 0 is y = 0 (the bottom of the image): flip, clamp, then resample
  // the cells onto the workspace's pixels.
  // A read-only view: cv::Mat has no const constructor.
  const cv::Mat cells(heat->ny(), heat->nx(), CV_32F,
                      const_cast<float*>(heat->data().data()));
  cv::Mat flipped, resized, value, shade;
  cv::flip(cells, flipped, 0);
  cv::resize(flipped, resized, heat_rect_.size(), 0, 0, cv::INTER_LINEAR);
  resized.convertTo(value, CV_8U, 255.0);  // saturates H to [0, 1]
  // Inferno from violet (low heat) to orange (H >= 1): its pale yellow top
  // would vanish on the light floor. Opacity grows with H.
  value.convertTo(shade, CV_8U, 0.55, 0.2 * 255.0);
  cv::applyColorMap(shade, heat_bgr_, cv::COLORMAP_INFERNO);
  value.convertTo(heat_alpha_, CV_8U, settings_.heat_alpha);
}

void FrameRenderer::DrawHeatmap(cv::Mat* image) const {
  if (heat_bgr_.empty()) return;
  cv::Mat roi = (*image)(heat_rect_);
  for (int r = 0; r < roi.rows; ++r) {
    unsigned char* dst = roi.ptr<unsigned char>(r);
    const unsigned char* src = heat_bgr_.ptr<unsigned char>(r);
    const unsigned char* alpha = heat_alpha_.ptr<unsigned char>(r);
    for (int c = 0; c < roi.cols; ++c) {
      const unsigned a = alpha[c];
      if (a == 0) continue;
      for (int ch = 0; ch < 3; ++ch) {
        const int i = 3 * c + ch;
        dst[i] = static_cast<unsigned char>(
            (src[i] * a + dst[i] * (255u - a) + 127u) / 255u);
      }
    }
  }
}

const cv::Mat& FrameRenderer::Render(const FrameOverlay& overlay) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  if (compact_) {
    // Nothing MuJoCo draws then moves: render it once.
    if (background_.empty()) scene_.Render(sim_.data(), camera_, &background_);
    background_.copyTo(frame_);
  } else {
    scene_.Render(sim_.data(), camera_, &frame_);
  }
  const auto t1 = Clock::now();
  DrawHeatmap(&frame_);
  DrawOverlay(overlay, &frame_);
  if (!legend_.empty()) legend_.copyTo(frame_(legend_rect_));
  scene_seconds_ += std::chrono::duration<double>(t1 - t0).count();
  overlay_seconds_ += SecondsSince(t1);
  return frame_;
}

bool FrameRenderer::MessagesShown(const FrameOverlay& o) {
  if (o.neighbors == nullptr) return false;
  switch (settings_.edges) {
    case EdgeMode::kAll:
      return true;
    case EdgeMode::kLost:
    case EdgeMode::kNone:
      return false;
    case EdgeMode::kAuto:
      break;
  }
  const auto& nb = *o.neighbors;
  size_t directed = 0;
  for (const auto& list : nb) directed += list.size();
  // Decided once per step's graph, so that it does not flicker as the robots
  // move during the step.
  if (o.step == messages_step_ && o.neighbors == messages_graph_ &&
      directed == messages_directed_)
    return messages_shown_;
  messages_step_ = o.step;
  messages_graph_ = o.neighbors;
  messages_directed_ = directed;
  // The ink of one line per pair (length x width) against the workspace's
  // pixels; counting stops once the budget is spent.
  const double s = view_.Scale(0.0);
  const double width = std::max(1.0, 0.75 * Unit(view_.height()));
  double budget = settings_.edge_ink * world_area_m2_ * s * s / width;
  messages_shown_ = true;
  for (int i = 0; i < static_cast<int>(nb.size()) && messages_shown_; ++i) {
    for (int j : nb[i]) {
      if (j < i && std::binary_search(nb[j].begin(), nb[j].end(), i)) continue;
      budget -= s * (o.robots[i] - o.robots[j]).norm();
      if (budget < 0.0) {
        messages_shown_ = false;
        break;
      }
    }
  }
  return messages_shown_;
}

bool FrameRenderer::DrawSensingAndMessages(const FrameOverlay& o,
                                           cv::Mat* image, bool* tint_out) {
  const int n = static_cast<int>(o.robots.size());
  const double unit = Unit(view_.height());
  const int thin = static_cast<int>(std::lround(unit));
  const double floor_scale = view_.Scale(0.0);
  // Translucent layers over the workspace (clipped to its walls, as sensing
  // and messages are): sensing discs, then delivered messages. Discs that
  // would cover the workspace more than once over (n pi r^2 > its area) are
  // one tint: the area sensed now.
  cv::Mat world = (*image)(world_rect_);
  const cv::Point offset(FixedLength(world_rect_.x),
                         FixedLength(world_rect_.y));
  const int range_px = FixedLength(o.sensor_range * floor_scale);
  const bool tint = n * kPi * o.sensor_range * o.sensor_range > world_area_m2_;
  *tint_out = tint;
  world.copyTo(layer_);
  for (int i = 0; i < n; ++i)
    if (o.active[i])
      cv::circle(layer_, pixels_[i] - offset, range_px,
                 tint ? kTint : RobotBgr(i), cv::FILLED, cv::LINE_AA, kShift);
  const double disc_alpha = tint ? kTintAlpha : kDiscAlpha;
  cv::addWeighted(layer_, disc_alpha, world, 1.0 - disc_alpha, 0.0, world);
  const bool messages = MessagesShown(o);
  drew_messages_ = false;
  if (messages) {
    const auto& nb = *o.neighbors;
    // Anti-aliased lines cost about 5x plain ones; past a few hundred edges
    // (a full graph of 25 robots) plain lines do.
    size_t directed = 0;
    for (const auto& list : nb) directed += list.size();
    const int line_type = directed <= 600 ? cv::LINE_AA : cv::LINE_8;
    const int edge_width =
        std::max(1, static_cast<int>(std::lround(0.75 * unit)));
    for (int i = 0; i < static_cast<int>(nb.size()); ++i) {
      for (int j : nb[i]) {
        // An undirected line per pair that exchanged anything; once per pair.
        const bool both = std::binary_search(nb[j].begin(), nb[j].end(), i);
        if (both && j < i) continue;
        if (!drew_messages_) world.copyTo(layer_);
        drew_messages_ = true;
        cv::line(layer_, pixels_[i] - offset, pixels_[j] - offset, kEdge,
                 edge_width, line_type, kShift);
      }
    }
    if (drew_messages_) cv::addWeighted(layer_, 0.7, world, 0.3, 0.0, world);
  }
  if (!tint)
    for (int i = 0; i < n; ++i)
      if (o.active[i])
        cv::circle(world, pixels_[i] - offset, range_px, RobotBgr(i, 0.8), thin,
                   cv::LINE_AA, kShift);
  return messages;
}

void FrameRenderer::DrawLostMessages(const FrameOverlay& o, cv::Mat* image) {
  // Red dashes from sender to receiver, shifted to the right of that
  // direction so that the two directions of a pair stay apart.
  if (o.lost == nullptr || settings_.edges == EdgeMode::kNone) return;
  const double unit = Unit(view_.height());
  const int thin = static_cast<int>(std::lround(unit));
  for (const auto& [receiver, sender] : *o.lost) {
    const Vec2 a = view_.ToPixel(o.robots[sender]),
               b = view_.ToPixel(o.robots[receiver]);
    Vec2 d = b - a;
    if (d.norm() < 1e-9) continue;
    d.normalize();
    const Vec2 side = 1.5 * unit * Vec2(-d.y(), d.x());
    DashedLine(image, a + side, b + side, kLost, thin, 5 * unit, 4 * unit);
  }
}

void FrameRenderer::DrawTrails(const FrameOverlay& o, cv::Mat* image) {
  // The recorded decision-step positions, closed by the position now.
  const int thin = static_cast<int>(std::lround(Unit(view_.height())));
  for (size_t i = 0; i < o.robots.size(); ++i) {
    polyline_.clear();
    for (const Vec2& p : trails_[i])
      polyline_.push_back(Fixed(view_.ToPixel(p)));
    polyline_.push_back(pixels_[i]);
    if (polyline_.size() >= 2)
      cv::polylines(*image, polyline_, false,
                    RobotBgr(static_cast<int>(i), 0.7), thin, cv::LINE_AA,
                    kShift);
  }
}

void FrameRenderer::DrawTargets(const FrameOverlay& o, cv::Mat* image) {
  // The best estimate's 2-sigma ellipse, a cross at its mean joined to the
  // truth, and a ring around the true position. Compact: a square at the
  // truth in the estimate's colour, the ellipse thin and drawn only where it
  // reaches beyond the square, no cross.
  const double unit = Unit(view_.height());
  const int thin = static_cast<int>(std::lround(unit));
  const int thick = static_cast<int>(std::lround(2 * unit));
  const double floor_scale = view_.Scale(0.0);
  const double area_px = world_area_m2_ * floor_scale * floor_scale;
  const int m = static_cast<int>(o.targets.size());
  const int max_axis = 4 * std::max(image->cols, image->rows);
  const double spacing_t = std::sqrt(area_px / std::max(1, m));
  const double half = std::max(1.5, std::min(3.0 * unit, 0.15 * spacing_t));
  for (const TargetOverlay& t : o.targets) {
    const cv::Scalar color = TargetColor(t, o.eps);
    const Vec2 mean_px = view_.ToPixel(t.mean);
    const Vec2 truth_px = view_.ToPixel(t.truth, 0.08);
    const cv::Point mean = Fixed(mean_px);
    const cv::Point truth = Fixed(truth_px);
    if (!compact_ || (mean_px - truth_px).norm() > half)
      cv::line(*image, mean, truth, color, thin, cv::LINE_AA, kShift);
    const Eigen::SelfAdjointEigenSolver<Mat2> eig(0.5 *
                                                  (t.cov + t.cov.transpose()));
    const Eigen::Vector2d lambda =
        eig.eigenvalues().cwiseMax(0.0);  // ascending
    const Eigen::Vector2d major = eig.eigenvectors().col(1);
    // 2 sigma along each principal axis; the image's y runs down, so the
    // world's counter-clockwise angle is clockwise on screen.
    const double a =
        std::min<double>(max_axis, 2.0 * std::sqrt(lambda[1]) * floor_scale);
    const double b =
        std::min<double>(max_axis, 2.0 * std::sqrt(lambda[0]) * floor_scale);
    const double angle = -std::atan2(major.y(), major.x()) * 180.0 / kPi;
    if (compact_) {
      if (a > 1.5 * half)
        DrawEllipse(image, mean, FixedLength(a), FixedLength(b), angle, color,
                    thin);
      DrawTargetMarker(image, truth_px, half, color, t.det <= o.eps ? 0 : thin);
      continue;
    }
    DrawEllipse(image, mean, FixedLength(a), FixedLength(b), angle, color,
                thick);
    DrawCross(image, mean, FixedLength(3.0 * unit), color, thick);
    cv::circle(*image, truth,
               FixedLength(std::max(4.0 * unit, 0.16 * floor_scale)), kBlack,
               thin, cv::LINE_AA, kShift);
  }
}

void FrameRenderer::DrawRobots(const FrameOverlay& o, cv::Mat* image) {
  // A dark ring around MuJoCo's disc; compact, a dot in the robot's colour,
  // ringed; a failed robot greyed and crossed.
  const int n = static_cast<int>(o.robots.size());
  const double unit = Unit(view_.height());
  const int thin = static_cast<int>(std::lround(unit));
  const int thick = static_cast<int>(std::lround(2 * unit));
  const double floor_scale = view_.Scale(0.0);
  const double robot_px = robot_radius_ * view_.Scale(2 * kRobotHalfHeight);
  const double area_px = world_area_m2_ * floor_scale * floor_scale;
  const double spacing_r = std::sqrt(area_px / std::max(1, n));
  const double dot =
      std::max(1.5, std::min(std::max(robot_px, 2.5 * unit), 0.3 * spacing_r));
  // A dot's ring stays thin, so that its colour shows.
  const int dot_ring = std::max(1, static_cast<int>(std::lround(0.6 * unit)));
  const bool headings = o.headings.size() == o.robots.size();
  for (int i = 0; i < n; ++i) {
    const Vec2 centre = view_.ToPixel(o.robots[i], 2 * kRobotHalfHeight);
    const cv::Point p = Fixed(centre);
    const double ring_px =
        compact_ ? dot : std::max(robot_px + unit, 3.0 * unit);
    const int ring = FixedLength(ring_px);
    if (o.active[i]) {
      if (compact_)
        cv::circle(*image, p, ring, RobotBgr(i), cv::FILLED, cv::LINE_AA,
                   kShift);
      cv::circle(*image, p, ring, kBlack, compact_ ? dot_ring : thin,
                 cv::LINE_AA, kShift);
      if (headings) {
        // A hand from the centre out past the ring: where the robot faces
        // (image y grows downward).
        const Vec2 dir(std::cos(o.headings[i]), -std::sin(o.headings[i]));
        const double reach = ring_px + std::max(2.0 * unit, 0.5 * ring_px);
        cv::line(*image, p, Fixed(centre + reach * dir), kBlack,
                 std::max(thick, dot_ring), cv::LINE_AA, kShift);
      }
      continue;
    }
    DrawFailedRobot(image, p, ring,
                    FixedLength(std::max(2.0 * robot_px, 5.0 * unit)), thick);
  }
}

void FrameRenderer::DrawHeadsUp(const FrameOverlay& o, cv::Mat* image) const {
  // In the band kept free above the workspace.
  const int band = view_.band_px();
  cv::rectangle(*image, cv::Rect(0, 0, image->cols, band),
                cv::Scalar(32, 32, 32), cv::FILLED);
  char text[256];
  int len = std::snprintf(
      text, sizeof(text),
      "step %d/%d   %.1f s   localized %d/%zu   %s   seed %llu", o.step,
      o.max_steps, o.seconds, o.localized, o.targets.size(), o.policy.c_str(),
      static_cast<unsigned long long>(o.seed));
  if (o.heatmap_robot >= 0 && len > 0 && len < static_cast<int>(sizeof(text)))
    std::snprintf(text + len, sizeof(text) - len, "   heatmap: robot %d",
                  o.heatmap_robot);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  int baseline = 0;
  // Text about half the band high, narrowed if the line would not fit.
  double font_scale = band / 50.0;
  const cv::Size size = cv::getTextSize(text, font, font_scale, 1, &baseline);
  const int margin = band / 3;
  if (size.width > image->cols - 2 * margin)
    font_scale *= static_cast<double>(image->cols - 2 * margin) / size.width;
  const cv::Size fitted = cv::getTextSize(text, font, font_scale, 1, &baseline);
  cv::putText(*image, text, cv::Point(margin, (band + fitted.height) / 2), font,
              font_scale, cv::Scalar(235, 235, 235), 1, cv::LINE_AA);
}

void FrameRenderer::DrawOverlay(const FrameOverlay& o, cv::Mat* image) {
  const int n = static_cast<int>(o.robots.size());
  AIA_CHECK(n == static_cast<int>(trails_.size()) &&
            o.active.size() == o.robots.size());
  pixels_.resize(n);
  for (int i = 0; i < n; ++i) pixels_[i] = Fixed(view_.ToPixel(o.robots[i]));
  bool tint = false;
  const bool messages = DrawSensingAndMessages(o, image, &tint);
  DrawLostMessages(o, image);
  DrawTrails(o, image);
  DrawTargets(o, image);
  DrawRobots(o, image);
  // The legend follows what was drawn.
  LegendKey key;
  key.heat = !heat_bgr_.empty();
  key.tint = tint;
  key.messages = messages ||
                 (settings_.edges == EdgeMode::kAuto && o.neighbors == nullptr);
  key.lost = settings_.edges != EdgeMode::kNone;
  if (!legend_built_ || !(key == legend_key_)) BuildLegend(key);
  DrawHeadsUp(o, image);
}

}  // namespace aia
