// Overlays drawn where the view maps them and in the colours the issue asks
// for: lost messages red and dashed, failed robots grey, ellipses green at or
// below eps and red above it, heat only where the heatmap is non-zero; and at
// scale (issue 19): the legend beside the world, --edges, a dense graph left
// out while lost messages stay, targets as markers coloured by det Sigma.
#include "aia/render/frame_renderer.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "aia/render/scene.h"
#include "aia/sim/simulation.h"
#include "aia/world/world.h"
#include "support/test_support.h"

namespace aia {
namespace {

constexpr int kWidth = 320, kHeight = 240;

bool Red(int r, int g, int b) { return r > 170 && g < 90 && b < 90; }
bool Green(int r, int g, int b) { return g > 120 && r < 110 && b < 110; }
bool Grey(int r, int g, int b) {
  return std::abs(r - g) < 12 && std::abs(g - b) < 12 && r > 60 && r < 130;
}
// Anti-aliased thin lines: partly covered pixels count too.
bool Reddish(int r, int g, int b) { return r > g + 60 && r > b + 60; }
bool EdgeBlue(int r, int g, int b) { return b > r + 25 && b >= g + 10; }

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

int CountIn(const cv::Mat& image, const cv::Rect& rect,
            bool (*pred)(int, int, int)) {
  int count = 0;
  const cv::Rect clipped = rect & cv::Rect(0, 0, image.cols, image.rows);
  for (int r = clipped.y; r < clipped.br().y; ++r)
    for (int c = clipped.x; c < clipped.br().x; ++c) {
      const cv::Vec3b& px = image.at<cv::Vec3b>(r, c);
      if (pred(px[2], px[1], px[0])) ++count;
    }
  return count;
}

// The pixels around the middle of the segment between two robots.
cv::Rect MiddleBox(const TopDownView& view, const Vec2& a, const Vec2& b) {
  const Vec2 c = view.ToPixel(0.5 * (a + b));
  return cv::Rect(static_cast<int>(c.x()) - 6, static_cast<int>(c.y()) - 6, 13,
                  13);
}

TEST_F(FrameRendererTest, EdgesFlagChoosesWhatIsDrawn) {
  const std::vector<std::vector<int>> neighbors = {{1}, {0}};
  const std::vector<std::pair<int, int>> lost = {{0, 1}};  // 0 lost 1's
  const std::vector<std::vector<int>> no_neighbors = {{}, {}};
  const std::vector<std::pair<int, int>> none;
  const cv::Rect middle =
      MiddleBox(FrameRenderer(sim_, world_.map, settings_).view(),
                overlay_.robots[0], overlay_.robots[1]);
  struct Case {
    EdgeMode mode;
    bool blue, red;
  };
  for (const Case& c :
       {Case{EdgeMode::kAuto, true, true}, Case{EdgeMode::kAll, true, true},
        Case{EdgeMode::kLost, false, true},
        Case{EdgeMode::kNone, false, false}}) {
    SCOPED_TRACE(EnumNameOf(c.mode));
    settings_.edges = c.mode;
    FrameRenderer renderer(sim_, world_.map, settings_);
    overlay_.neighbors = &no_neighbors;
    overlay_.lost = &none;
    const cv::Mat bare = renderer.Render(overlay_).clone();
    overlay_.neighbors = &neighbors;
    overlay_.lost = &lost;
    const cv::Mat drawn = renderer.Render(overlay_).clone();
    EXPECT_EQ(renderer.drew_messages(), c.blue);
    EXPECT_EQ(CountIn(drawn, middle, EdgeBlue) > 5, c.blue);
    EXPECT_EQ(CountIn(drawn, middle, Reddish) > 3, c.red);
    if (c.mode == EdgeMode::kNone) {
      // No edge pixels at all: the world looks as without a graph.
      cv::Mat diff;
      cv::absdiff(bare(renderer.world_rect()), drawn(renderer.world_rect()),
                  diff);
      EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0);
    }
  }
}

TEST(EdgeModeTest, NamesRoundTrip) {
  for (EdgeMode m :
       {EdgeMode::kAuto, EdgeMode::kAll, EdgeMode::kLost, EdgeMode::kNone}) {
    EdgeMode parsed = EdgeMode::kAuto;
    EXPECT_TRUE(ParseEnumName(EnumNameOf(m), &parsed));
    EXPECT_EQ(parsed, m);
  }
  EdgeMode parsed = EdgeMode::kAll;
  EXPECT_FALSE(ParseEnumName("some", &parsed));
  EXPECT_FALSE(ParseEnumName("", &parsed));
  EXPECT_EQ(parsed, EdgeMode::kAll);
}

TEST(TrailStepsTest, BudgetSharedByTheRobots) {
  EXPECT_EQ(TrailSteps(50, 1), 50);
  EXPECT_EQ(TrailSteps(50, 10), 50);
  EXPECT_EQ(TrailSteps(50, 80), 6);
  EXPECT_EQ(TrailSteps(50, 1000), 5);
  EXPECT_EQ(TrailSteps(3, 1000), 3);
  EXPECT_EQ(TrailSteps(0, 1000), 0);  // the whole mission, as asked
}

// 300 robots and 300 targets on a 60 x 60 m world, 640 x 480: about 7 pixels
// per metre, too small and too many for MuJoCo's bodies.
class CrowdTest : public ::testing::Test {
 protected:
  static constexpr int kCount = 300;
  CrowdTest()
      : scenario_(testing::ScenarioFromYaml("seed: 5\n"
                                            "workspace: {size: [60.0, 60.0]}\n"
                                            "robots: {count: 300}\n"
                                            "targets: {count: 300}\n")),
        world_(World::Build(scenario_)),
        sim_(world_, scenario_) {
    settings_.scene.width = 640;
    settings_.scene.height = 480;
    for (int i = 0; i < kCount; ++i)
      overlay_.robots.push_back(sim_.RobotPosition(i));
    overlay_.active.assign(kCount, 1);
    for (int k = 0; k < kCount; ++k) {
      TargetOverlay t;
      t.truth = t.mean = sim_.TargetPosition(k);
      t.cov = 0.5 * Mat2::Identity();
      t.det = 0.25;
      overlay_.targets.push_back(t);
    }
    overlay_.eps = 0.1;
    overlay_.max_steps = 10;
    overlay_.policy = "test";
    // The full graph.
    full_.resize(kCount);
    for (int i = 0; i < kCount; ++i)
      for (int j = 0; j < kCount; ++j)
        if (j != i) full_[i].push_back(j);
  }

  Scenario scenario_;
  World world_;
  Simulation sim_;
  FrameSettings settings_;
  FrameOverlay overlay_;
  std::vector<std::vector<int>> full_;
};

TEST_F(CrowdTest, LegendLiesBesideTheWorld) {
  FrameRenderer renderer(sim_, world_.map, settings_);
  EXPECT_TRUE(renderer.compact());
  const cv::Rect world = renderer.world_rect();
  const cv::Rect legend = renderer.legend_rect();
  ASSERT_FALSE(legend.empty());
  EXPECT_TRUE((legend & world).empty())
      << "legend " << legend << " world " << world;
  EXPECT_EQ(legend & cv::Rect(0, 0, 640, 480), legend);
  EXPECT_GE(legend.x, world.br().x);
  // The world still fills the height below the band: the column cost it
  // nothing in a 4:3 image.
  EXPECT_GE(world.height, 480 - HudBandPixels(480) - 12);
  // What is drawn there is the legend: the frame's pixels are the legend's
  // light paper, and the world's right edge (its wall) is not covered.
  const cv::Mat& image = renderer.Render(overlay_);
  const cv::Vec3b paper =
      image.at<cv::Vec3b>(legend.y + legend.height / 2, legend.x + 2);
  EXPECT_GT(paper[0], 200);
  int darkest = 3 * 255;  // the wall's top, in the world's last columns
  for (int col = world.br().x - 3; col < world.br().x; ++col) {
    const cv::Vec3b px = image.at<cv::Vec3b>(world.y + world.height / 2, col);
    darkest = std::min(darkest, px[0] + px[1] + px[2]);
  }
  EXPECT_LT(darkest, 3 * 170);
}

TEST_F(CrowdTest, DenseGraphIsLeftOutButLostMessagesStay) {
  FrameRenderer renderer(sim_, world_.map, settings_);
  const std::vector<std::pair<int, int>> none;
  const std::vector<std::pair<int, int>> lost = {{0, 1}};
  for (TargetOverlay& t : overlay_.targets) t.det = 0.05;  // green, not red
  overlay_.neighbors = &full_;
  overlay_.lost = &none;
  const cv::Mat without = renderer.Render(overlay_).clone();
  EXPECT_FALSE(renderer.drew_messages());
  overlay_.lost = &lost;
  const cv::Mat with = renderer.Render(overlay_).clone();
  // Red pixels along the lost message's path (midway between 1 and 0).
  const cv::Rect middle =
      MiddleBox(renderer.view(), overlay_.robots[0], overlay_.robots[1]);
  EXPECT_GT(CountIn(with, middle, Reddish),
            CountIn(without, middle, Reddish) + 2);
  // --edges all draws the haze.
  settings_.edges = EdgeMode::kAll;
  FrameRenderer all(sim_, world_.map, settings_);
  all.Render(overlay_);
  EXPECT_TRUE(all.drew_messages());
  // A sparse graph (each robot and its nearest one) is drawn under auto.
  std::vector<std::vector<int>> chain(kCount);
  for (int i = 0; i < kCount; ++i) {
    int nearest = i == 0 ? 1 : 0;
    for (int j = 0; j < kCount; ++j)
      if (j != i && (overlay_.robots[j] - overlay_.robots[i]).norm() <
                        (overlay_.robots[nearest] - overlay_.robots[i]).norm())
        nearest = j;
    chain[i].push_back(nearest);
    chain[nearest].push_back(i);
  }
  for (auto& list : chain) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  overlay_.neighbors = &chain;
  overlay_.step = 1;
  renderer.Render(overlay_);
  EXPECT_TRUE(renderer.drew_messages());
}

TEST_F(CrowdTest, TargetMarkerShowsWhetherLocalized) {
  FrameRenderer renderer(sim_, world_.map, settings_);
  const Vec2 truth = overlay_.targets[0].truth;
  const Vec2 c = renderer.view().ToPixel(truth, 0.08);
  const cv::Rect box(static_cast<int>(c.x()) - 1, static_cast<int>(c.y()) - 1,
                     3, 3);
  // A robot dot could sit on the marker: move the robots away from it.
  for (Vec2& p : overlay_.robots)
    if ((p - truth).norm() < 1.5) p = Vec2(0.5, 0.5);
  for (auto& t : overlay_.targets)
    if (&t != &overlay_.targets[0] && (t.truth - truth).norm() < 3.0)
      t.truth = t.mean = Vec2(59.5, 59.5);
  overlay_.targets[0].det = 0.5;  // above eps
  overlay_.targets[0].weight = 1.0;
  const cv::Mat uncertain = renderer.Render(overlay_).clone();
  overlay_.targets[0].det = 0.05;  // at or below eps
  overlay_.targets[0].cov = 0.01 * Mat2::Identity();
  const cv::Mat localized = renderer.Render(overlay_).clone();
  EXPECT_EQ(CountIn(uncertain, box, Red), 9);
  EXPECT_EQ(CountIn(uncertain, box, Green), 0);
  EXPECT_EQ(CountIn(localized, box, Green), 9);
  EXPECT_EQ(CountIn(localized, box, Red), 0);
}

TEST_F(FrameRendererTest, SmallImagesKeepTheWholeWorldAndNoLegend) {
  // 320 x 240: a 140-pixel column would shrink the square world by more
  // than 15%, so there is none and nothing covers the world.
  FrameRenderer renderer(sim_, world_.map, settings_);
  EXPECT_TRUE(renderer.legend_rect().empty());
  EXPECT_EQ(renderer.view().side_px(), 0);
  EXPECT_FALSE(renderer.compact());  // 10 m in 227 px: 2.3 px robots
}

// Mesa's llvmpipe threads, made with this process's first GL context, do
// not exist in a child forked since: its render waited for them for ever,
// and is refused instead, naming the way out.
TEST_F(FrameRendererTest, AChildForkedAfterARenderIsRefused) {
  const char* threads = std::getenv("LP_NUM_THREADS");
  if (threads != nullptr && std::string(threads) == "0")
    GTEST_SKIP() << "LP_NUM_THREADS=0: llvmpipe has no threads to miss";
  FrameRenderer renderer(sim_, world_.map, settings_);
  renderer.Render(overlay_);
  EXPECT_EQ(RenderForkProblem(), "");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    alarm(60);  // a hang ends the child, and fails the test
    // Exit codes: 0 both refused, 1 a render went on, 2 another message.
    const auto refused = [](const auto& render) {
      try {
        render();
      } catch (const std::runtime_error& e) {
        const std::string why = e.what();
        return why.find("forked from one that had rendered") !=
                           std::string::npos &&
                       why.find("LP_NUM_THREADS=0") != std::string::npos
                   ? 0
                   : 2;
      }
      return 1;
    };
    const int made =
        refused([&] { FrameRenderer another(sim_, world_.map, settings_); });
    const int old = refused([&] { renderer.Render(overlay_); });
    _exit(made != 0 ? made : old);  // not Mesa's exit handler
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << "the child hung or crashed: " << status;
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(RenderForkProblem(), "");  // the parent renders on
  renderer.Render(overlay_);
}

}  // namespace
}  // namespace aia
