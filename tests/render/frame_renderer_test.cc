// Overlays drawn where the view maps them and in the colours the issue asks
// for: lost messages red and dashed, failed robots grey, ellipses green at or
// below eps and red above it, heat only where the heatmap is non-zero.
#include "aia/render/frame_renderer.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "aia/sim/simulation.h"
#include "aia/world/world.h"
#include "support/test_support.h"

namespace aia {
namespace {

constexpr int kWidth = 320, kHeight = 240;

class FrameRendererTest : public ::testing::Test {
 protected:
  FrameRendererTest()
      : scenario_(testing::ScenarioFromYaml(
            "workspace: {size: [10.0, 10.0]}\n"
            "robots: {count: 2, start: [[2.25, 4.25], [7.75, 4.25]]}\n"
            "targets: {list: [{position: [5.0, 8.5], prior_mean: [5.0, "
            "8.5]}]}\n")),
        world_(World::Build(scenario_)),
        sim_(world_, scenario_) {
    settings_.scene.width = kWidth;
    settings_.scene.height = kHeight;
    overlay_.robots = {sim_.RobotPosition(0), sim_.RobotPosition(1)};
    overlay_.active = {1, 1};
    TargetOverlay t;
    t.truth = t.mean = sim_.TargetPosition(0);
    t.cov = 0.04 * Mat2::Identity();  // 2 sigma = 0.4 m
    t.det = 0.0016;
    overlay_.targets = {t};
    overlay_.eps = 0.1;
    overlay_.max_steps = 10;
    overlay_.policy = "test";
  }

  // Pixels of `image` within `radius` pixels of world point p where `pred`
  // holds.
  template <typename Pred>
  static int Count(const cv::Mat& image, const TopDownView& view, const Vec2& p,
                   double radius, Pred pred) {
    const Vec2 c = view.ToPixel(p);
    int count = 0;
    for (int r = 0; r < image.rows; ++r)
      for (int col = 0; col < image.cols; ++col) {
        if ((Vec2(col + 0.5, r + 0.5) - c).norm() > radius) continue;
        const cv::Vec3b& px = image.at<cv::Vec3b>(r, col);
        if (pred(px[2], px[1], px[0])) ++count;
      }
    return count;
  }
  static bool Red(int r, int g, int b) { return r > 170 && g < 90 && b < 90; }
  static bool Green(int r, int g, int b) {
    return g > 120 && r < 110 && b < 110;
  }
  static bool Grey(int r, int g, int b) {
    return std::abs(r - g) < 12 && std::abs(g - b) < 12 && r > 60 && r < 130;
  }

  Scenario scenario_;
  World world_;
  Simulation sim_;
  FrameSettings settings_;
  FrameOverlay overlay_;
};

TEST_F(FrameRendererTest, LostMessagesAreRedDashes) {
  FrameRenderer renderer(sim_, world_.map, settings_);
  const std::vector<std::vector<int>> neighbors = {
      {}, {0}};  // 1 heard 0; 0 lost 1's message
  const std::vector<std::pair<int, int>> lost = {{0, 1}};
  const std::vector<std::pair<int, int>> none;
  overlay_.neighbors = &neighbors;
  overlay_.lost = &none;
  const Vec2 middle = 0.5 * (overlay_.robots[0] + overlay_.robots[1]);
  // The segment's middle 3 m: away from the discs' rims.
  const auto red_on_segment = [&](const cv::Mat& image) {
    int count = 0;
    for (double x = 3.5; x <= 6.5; x += 0.5)
      count += Count(image, renderer.view(), {x, middle.y()}, 4.0, Red);
    return count;
  };
  const int without = red_on_segment(renderer.Render(overlay_).clone());
  overlay_.lost = &lost;
  const cv::Mat with = renderer.Render(overlay_).clone();
  EXPECT_EQ(without, 0);
  EXPECT_GT(red_on_segment(with), 10);
  // Dashed: some columns along the segment carry no red at all.
  const Vec2 a = renderer.view().ToPixel({3.5, middle.y()});
  const Vec2 b = renderer.view().ToPixel({6.5, middle.y()});
  int gaps = 0;
  for (int col = static_cast<int>(a.x()); col < static_cast<int>(b.x());
       ++col) {
    bool red = false;
    for (int r = static_cast<int>(a.y()) - 4; r <= static_cast<int>(a.y()) + 4;
         ++r) {
      const cv::Vec3b& px = with.at<cv::Vec3b>(r, col);
      red = red || Red(px[2], px[1], px[0]);
    }
    gaps += red ? 0 : 1;
  }
  EXPECT_GT(gaps, 3);
}

TEST_F(FrameRendererTest, FailedRobotIsGreyedOut) {
  FrameRenderer renderer(sim_, world_.map, settings_);
  const Vec2 p = overlay_.robots[1];
  const int active =
      Count(renderer.Render(overlay_), renderer.view(), p, 5.0, Grey);
  overlay_.active = {1, 0};
  const int failed =
      Count(renderer.Render(overlay_), renderer.view(), p, 5.0, Grey);
  EXPECT_GT(failed, active + 15);
}

TEST_F(FrameRendererTest, EllipseIsGreenAtOrBelowEpsAndRedAbove) {
  FrameRenderer renderer(sim_, world_.map, settings_);
  const Vec2 mean = overlay_.targets[0].mean;
  const double radius = 0.4 * renderer.view().Scale() + 3.0;
  cv::Mat image = renderer.Render(overlay_).clone();
  EXPECT_GT(Count(image, renderer.view(), mean, radius, Green), 10);
  EXPECT_EQ(Count(image, renderer.view(), mean, radius, Red), 0);
  overlay_.targets[0].det = 0.5;
  overlay_.targets[0].weight = 1.0;
  image = renderer.Render(overlay_).clone();
  EXPECT_EQ(Count(image, renderer.view(), mean, radius, Green), 0);
  EXPECT_GT(Count(image, renderer.view(), mean, radius, Red), 10);
}

TEST_F(FrameRendererTest, HeatmapTintsOnlyWhereThereIsHeat) {
  FrameRenderer renderer(sim_, world_.map, settings_);
  const cv::Mat plain = renderer.Render(overlay_).clone();
  Grid<float> heat(20, 20, 0.5, 0.0f);  // the 10 x 10 m workspace
  for (int iy = 0; iy < 6; ++iy)
    for (int ix = 14; ix < 20; ++ix)
      heat(ix, iy) = 1.0f;  // x in [7, 10], y in [0, 3]
  renderer.SetHeatmap(&heat);
  const cv::Mat heated = renderer.Render(overlay_).clone();
  cv::Mat diff, channels[3], changed;
  cv::absdiff(plain, heated, diff);
  cv::split(diff, channels);
  cv::max(channels[0], channels[1], changed);
  cv::max(changed, channels[2], changed);  // the largest change over B, G, R
  const auto differs_near = [&](const Vec2& p) {
    const Vec2 c = renderer.view().ToPixel(p);
    const cv::Rect box(static_cast<int>(c.x()) - 3, static_cast<int>(c.y()) - 3,
                       7, 7);
    return cv::countNonZero(changed(box) > 20);
  };
  EXPECT_GT(differs_near({8.5, 1.5}), 40);  // inside the hot square
  EXPECT_EQ(differs_near({2.0, 8.0}), 0);   // far from it
  EXPECT_EQ(differs_near({5.0, 1.5}), 0);
  renderer.SetHeatmap(nullptr);
  cv::absdiff(plain, renderer.Render(overlay_), diff);
  EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0);
}

}  // namespace
}  // namespace aia
