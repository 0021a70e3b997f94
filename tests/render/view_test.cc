// The world -> pixel map of the top-down view against MuJoCo's own render:
// an obstacle's eight corners and a target's centre land where TopDownView
// says, to a pixel, so overlays sit on the scene.
#include "aia/render/view.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "aia/render/frame_renderer.h"
#include "aia/render/scene.h"
#include "aia/sim/simulation.h"
#include "aia/world/mjcf.h"
#include "aia/world/world.h"
#include "support/test_support.h"

namespace aia {
namespace {

constexpr int kWidth = 320, kHeight = 240;

Scenario MappingScenario() {
  return testing::ScenarioFromYaml(
      "workspace: {size: [12.0, 9.0], obstacles: {boxes: [{center: [8.5, 6.5], "
      "size: [2.0, 1.0]}, "
      "{center: [2.5, 2.0], size: [1.0, 1.4]}]}}\n"
      "robots: {count: 1, start: [[0.75, 8.25]]}\n"
      "targets: {list: [{position: [4.0, 6.0]}]}\n");
}

TEST(TopDownViewTest, FramesTheWorkspaceBelowTheBand) {
  const TopDownView view({20.0, 20.0}, 640, 480, 45.0, 26, 0.5);
  // Straight down: the same scale everywhere on the floor, square pixels.
  const Vec2 a = view.ToPixel({0.0, 0.0}), b = view.ToPixel({20.0, 20.0});
  EXPECT_NEAR(b.x() - a.x(), a.y() - b.y(), 1e-9);
  EXPECT_NEAR((b.x() - a.x()) / 20.0, view.Scale(), 1e-9);
  EXPECT_NEAR(view.focal(), 240.0 / std::tan(22.5 * M_PI / 180.0), 1e-9);
  // The walls' tops (0.1 m outside, 0.5 m high) fit, below the band.
  const Vec2 top_left = view.ToPixel({-0.1, 20.1}, 0.5);
  const Vec2 bottom_right = view.ToPixel({20.1, -0.1}, 0.5);
  EXPECT_GE(top_left.x(), 0.0);
  EXPECT_GE(top_left.y(), 26.0);
  EXPECT_LE(bottom_right.x(), 640.0);
  EXPECT_LE(bottom_right.y(), 480.0);
  // Tight vertically: within a metre of margin.
  EXPECT_LT(top_left.y() - 26.0, view.Scale());
  EXPECT_LT(480.0 - bottom_right.y(), view.Scale());
  // Centred horizontally, and higher points lie farther from the centre.
  EXPECT_NEAR(a.x() + b.x(), 640.0, 1e-9);
  EXPECT_GT(view.ToPixel({20.0, 10.0}, 0.5).x(),
            view.ToPixel({20.0, 10.0}, 0.0).x());
}

TEST(TopDownViewTest, KeepsTheLegendColumnFreeAndFitsExactly) {
  const int band = 26, side = 140;
  const double t = 0.5, margin = 0.25;
  for (const Vec2& size : {Vec2(20.0, 20.0), Vec2(40.0, 10.0)}) {
    SCOPED_TRACE(size.x());
    const TopDownView view(size, 640, 480, 45.0, band, t, margin, side);
    EXPECT_EQ(view.side_px(), side);
    // The framed rectangle at the walls' tops lies in [0, 640 - side] x
    // [band, 480], touching the free pixels on one pair of sides (the
    // smallest height that fits), and the floor is centred in them.
    const Vec2 tl = view.ToPixel({-margin, size.y() + margin}, t);
    const Vec2 br = view.ToPixel({size.x() + margin, -margin}, t);
    EXPECT_GE(tl.x(), -1e-9);
    EXPECT_GE(tl.y(), band - 1e-9);
    EXPECT_LE(br.x(), 640 - side + 1e-9);
    EXPECT_LE(br.y(), 480 + 1e-9);
    const double slack =
        std::min({tl.x(), tl.y() - band, 640 - side - br.x(), 480 - br.y()});
    EXPECT_NEAR(slack, 0.0, 1e-6);
    const Vec2 a = view.ToPixel({0.0, 0.0}), b = view.ToPixel(size);
    EXPECT_NEAR(0.5 * (a.x() + b.x()), 0.5 * (640 - side), 1e-9);
    EXPECT_NEAR(0.5 * (a.y() + b.y()), 0.5 * (480 + band), 1e-9);
  }
}

TEST(TopDownViewTest, ObstacleCornersAndTargetLandWhereTheMapSays) {
  const Scenario scenario = MappingScenario();
  const World world = World::Build(scenario);
  const Simulation sim(world, scenario);
  SceneSettings settings;
  settings.width = kWidth;
  settings.height = kHeight;
  SceneRenderer renderer(sim.model(), settings);
  const TopDownView view(world.map.size(), kWidth, kHeight,
                         sim.model()->vis.global.fovy, HudBandPixels(kHeight),
                         kObstacleHeight);
  mjvCamera camera;
  view.SetCamera(&camera);
  cv::Mat image;
  renderer.Render(sim.data(), camera, &image);
  ASSERT_EQ(image.rows, kHeight);
  ASSERT_EQ(image.cols, kWidth);
  cv::Mat gray;
  cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);

  ASSERT_EQ(world.map.obstacles().size(), 2u);
  for (const Box& box : world.map.obstacles()) {
    // Seen in perspective, the box covers the projections of its eight
    // corners: its top face and the sides that face the camera.
    double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
    for (double z : {0.0, kObstacleHeight}) {
      for (const Vec2& c : {box.lo, box.hi, Vec2(box.lo.x(), box.hi.y()),
                            Vec2(box.hi.x(), box.lo.y())}) {
        const Vec2 p = view.ToPixel(c, z);
        u0 = std::min(u0, p.x());
        u1 = std::max(u1, p.x());
        v0 = std::min(v0, p.y());
        v1 = std::max(v1, p.y());
      }
    }
    // The dark pixels near the expected rectangle (the light floor around).
    const cv::Rect window(static_cast<int>(u0) - 6, static_cast<int>(v0) - 6,
                          static_cast<int>(u1 - u0) + 13,
                          static_cast<int>(v1 - v0) + 13);
    const cv::Mat dark = gray(window) < 150;
    const cv::Rect found = cv::boundingRect(dark) + window.tl();
    ASSERT_GT(found.area(), 0);
    // A pixel is dark when most of it is covered: edges within a pixel.
    EXPECT_NEAR(found.x, u0, 1.0) << "left edge";
    EXPECT_NEAR(found.x + found.width, u1, 1.0) << "right edge";
    EXPECT_NEAR(found.y, v0, 1.0) << "top edge";
    EXPECT_NEAR(found.y + found.height, v1, 1.0) << "bottom edge";
  }

  // The target's red sphere (centre 0.08 m above the floor).
  const Vec2 expected = view.ToPixel(sim.TargetPosition(0), 0.08);
  cv::Mat channels[3];
  cv::split(image, channels);
  const cv::Mat red =
      (channels[2] > 120) & (channels[1] < 80) & (channels[0] < 80);
  const cv::Moments mo = cv::moments(red, true);
  ASSERT_GT(mo.m00, 4.0);
  // Moments index pixel centres at integers; the map's at +0.5.
  EXPECT_NEAR(mo.m10 / mo.m00 + 0.5, expected.x(), 0.5);
  EXPECT_NEAR(mo.m01 / mo.m00 + 0.5, expected.y(), 0.5);
}

}  // namespace
}  // namespace aia
