// The channels of a tiny hand-built world, worked out by hand in both frames
// (docs/learning.md, Channels).
#include "aia/learning/channels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <thread>
#include <vector>

#include "aia/world/map.h"

namespace aia {
namespace {

// A 2 x 2 m workspace, occupancy cells of 0.5 m (4 x 4), pixels of 1 m
// (2 x 2): pixel (0, 0) holds fine cells (0..1, 0..1), two of them
// occupied; pixel (1, 1) one of four.
struct TinyWorld {
  Grid<std::uint8_t> occupancy{4, 4, 0.5, 0};
  Vec2 size{2.0, 2.0};
  Vec2 self{0.25, 1.75};                                 // pixel (0, 1)
  std::vector<Vec2> neighbours{{1.5, 0.5}, {1.6, 0.6}};  // both pixel (1, 0)
  std::vector<HeatSource> targets;
  std::vector<double> log_det_prior{std::log(100.0)};
  double eps = 0.01;
  TinyWorld() {
    occupancy(0, 0) = occupancy(1, 0) = 1;
    occupancy(3, 3) = 1;
    // det Sigma = 1: w = log(1 / 0.01) / log(100 / 0.01) = 0.5.
    HeatSource t;
    t.mean = {1.5, 1.5};
    t.cov = Mat2::Identity();
    t.log_det = 0.0;
    targets.push_back(t);
  }
};

// With s = 1, S = Sigma + s^2 I = 2 I: H = 0.5 exp(-|d|^2 / 4).
const float kH0 = 0.5f;                                       // at the mean
const float kH1 = static_cast<float>(0.5 * std::exp(-0.25));  // 1 m away
const float kH2 = static_cast<float>(0.5 * std::exp(-0.5));   // diagonal

ChannelParams Params(ChannelFrame frame, int window = 3) {
  ChannelParams p;
  p.frame = frame;
  p.cell = 1.0;
  p.window = window;
  p.blur = 1.0;
  p.cutoff = 4.0;
  return p;
}

// A centred window of `window` pixels of 0.5 m with the reach channel at
// decay length `length` (over the workspace with `world`), observation
// range 2 m: the learned models' settings.
ChannelParams ReachParams(int window, double length, bool world) {
  ChannelParams p = Params(ChannelFrame::kCentred, window);
  p.cell = 0.5;
  p.geodesic = true;
  p.geodesic_length = length;
  p.observe_range = 2.0;
  p.reach_world = world;
  return p;
}

// Channel c at (x, y) of an image `w` pixels wide and `h` high.
float At(const std::vector<float>& img, int h, int w, int c, int x, int y) {
  return img[(static_cast<std::size_t>(c) * h + y) * w + x];
}

// The reach channel's sort of its sources: the values in std::sort's order
// (largest first), each pair kept whole, for short and long lists with
// ties, zeros, tiny and large values.
TEST(ChannelsTest, SourcesSortLargestFirst) {
  std::uint64_t state = 12345;
  const auto next = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<std::uint32_t>(state >> 33);
  };
  for (const int n : {0, 1, 5, 63, 64, 65, 1000, 5000}) {
    std::vector<std::pair<float, int>> items;
    for (int i = 0; i < n; ++i) {
      const std::uint32_t r = next() % 6;
      const float value = r == 0   ? 0.0f
                          : r == 1 ? 1.0f
                          : r == 2 ? 1e-7f * (next() % 5)
                          : r == 3 ? 3e4f
                                   : static_cast<float>(next()) / 4294967296.0f;
      items.push_back({value, i});
    }
    std::vector<std::pair<float, int>> sorted = items;
    internal::SortByValueDescending(&sorted);
    ASSERT_EQ(sorted.size(), items.size());
    std::vector<std::pair<float, int>> want = items;
    std::sort(want.begin(), want.end(),
              [](const auto& a, const auto& b) { return a.first > b.first; });
    for (int i = 0; i < n; ++i) {
      EXPECT_EQ(sorted[i].first, want[i].first) << "n " << n << " at " << i;
      EXPECT_EQ(sorted[i].first, items[sorted[i].second].first);
    }
    // Each index once.
    std::vector<int> seen(n, 0);
    for (const auto& item : sorted) ++seen[item.second];
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), n);
  }
}

TEST(ChannelsTest, GlobalFrameMatchesHandComputedValues) {
  TinyWorld t;
  ChannelRenderer r(t.occupancy, t.size, Params(ChannelFrame::kGlobal));
  ASSERT_EQ(r.height(), 2);
  ASSERT_EQ(r.width(), 2);
  std::vector<float> img(r.ImageSize(), -1.0f);
  r.Render(t.self, t.neighbours, t.targets, t.log_det_prior, t.eps, img.data());
  const auto at = [&](int c, int x, int y) { return At(img, 2, 2, c, x, y); };
  // Occupancy shares.
  EXPECT_FLOAT_EQ(at(0, 0, 0), 0.5f);
  EXPECT_FLOAT_EQ(at(0, 1, 0), 0.0f);
  EXPECT_FLOAT_EQ(at(0, 0, 1), 0.0f);
  EXPECT_FLOAT_EQ(at(0, 1, 1), 0.25f);
  // Own position and neighbours (self excluded, counted per pixel).
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x) {
      EXPECT_FLOAT_EQ(at(1, x, y), x == 0 && y == 1 ? 1.0f : 0.0f);
      EXPECT_FLOAT_EQ(at(2, x, y), x == 1 && y == 0 ? 2.0f : 0.0f);
    }
  // Heat at the pixel centres.
  EXPECT_NEAR(at(3, 1, 1), kH0, 1e-6);
  EXPECT_NEAR(at(3, 0, 1), kH1, 1e-6);
  EXPECT_NEAR(at(3, 1, 0), kH1, 1e-6);
  EXPECT_NEAR(at(3, 0, 0), kH2, 1e-6);
}

TEST(ChannelsTest, CentredFrameMatchesHandComputedValues) {
  TinyWorld t;
  // Window 3: the robot's pixel (0, 1) at (1, 1); window (u, v) is global
  // (u - 1, v).
  ChannelRenderer r(t.occupancy, t.size, Params(ChannelFrame::kCentred));
  ASSERT_EQ(r.height(), 3);
  ASSERT_EQ(r.width(), 3);
  std::vector<float> img(r.ImageSize(), -1.0f);
  r.Render(t.self, t.neighbours, t.targets, t.log_det_prior, t.eps, img.data());
  const auto at = [&](int c, int x, int y) { return At(img, 3, 3, c, x, y); };
  const float occ[3][3] = {{1.0f, 0.5f, 0.0f},   // v = 0
                           {1.0f, 0.0f, 0.25f},  // v = 1
                           {1.0f, 1.0f, 1.0f}};  // v = 2: outside
  const float heat[3][3] = {{0.0f, kH2, kH1}, {0.0f, kH1, kH0}, {0, 0, 0}};
  for (int v = 0; v < 3; ++v)
    for (int u = 0; u < 3; ++u) {
      EXPECT_FLOAT_EQ(at(0, u, v), occ[v][u]) << u << "," << v;
      EXPECT_FLOAT_EQ(at(1, u, v), u == 1 && v == 1 ? 1.0f : 0.0f);
      EXPECT_FLOAT_EQ(at(2, u, v), u == 2 && v == 0 ? 2.0f : 0.0f);
      EXPECT_NEAR(at(3, u, v), heat[v][u], 1e-6) << u << "," << v;
    }
}

TEST(ChannelsTest, CentredFrameFoldsWhatLiesBeyondTheWindowOntoItsBorder) {
  TinyWorld t;
  // A one-pixel window: every neighbour and all heat fold onto it; the
  // heat folds by the largest value, the neighbours by count.
  ChannelRenderer r(t.occupancy, t.size, Params(ChannelFrame::kCentred, 1));
  std::vector<float> img(r.ImageSize());
  r.Render(t.self, t.neighbours, t.targets, t.log_det_prior, t.eps, img.data());
  EXPECT_FLOAT_EQ(img[0], 0.0f);  // the robot's own pixel is free
  EXPECT_FLOAT_EQ(img[1], 1.0f);
  EXPECT_FLOAT_EQ(img[2], 2.0f);
  EXPECT_NEAR(img[3], kH0, 1e-6);
}

// ChannelParams::neighbour_cap: a pixel holds at most the cap, in both
// frames, border pixels (the neighbours beyond the window) included; 0
// counts them all.
TEST(ChannelsTest, NeighboursAreCountedUpToTheCap) {
  TinyWorld t;
  // Three neighbours in pixel (1, 0), one in pixel (1, 1).
  t.neighbours = {{1.5, 0.5}, {1.6, 0.6}, {1.4, 0.4}, {1.5, 1.5}};
  for (const int cap : {0, 1, 2, 5}) {
    ChannelParams global = Params(ChannelFrame::kGlobal);
    global.neighbour_cap = cap;
    ChannelRenderer g(t.occupancy, t.size, global);
    std::vector<float> img(g.ImageSize());
    g.Render(t.self, t.neighbours, t.targets, t.log_det_prior, t.eps,
             img.data());
    const float three = cap == 0 ? 3.0f : std::min(3.0f, float(cap));
    EXPECT_FLOAT_EQ(At(img, 2, 2, 2, 1, 0), three) << cap;
    EXPECT_FLOAT_EQ(At(img, 2, 2, 2, 1, 1), 1.0f) << cap;
    EXPECT_FLOAT_EQ(At(img, 2, 2, 2, 0, 0), 0.0f) << cap;
    // A one-pixel window: all four fold onto it.
    ChannelParams centred = Params(ChannelFrame::kCentred, 1);
    centred.neighbour_cap = cap;
    ChannelRenderer c(t.occupancy, t.size, centred);
    std::vector<float> one(c.ImageSize());
    c.Render(t.self, t.neighbours, t.targets, t.log_det_prior, t.eps,
             one.data());
    EXPECT_FLOAT_EQ(one[2], cap == 0 ? 4.0f : std::min(4.0f, float(cap)))
        << cap;
    // The other channels do not change.
    EXPECT_FLOAT_EQ(one[1], 1.0f);
    EXPECT_NEAR(one[3], kH0, 1e-6);
  }
}

// HeatFold folds a heatmap for any window exactly as the direct fold does:
// random heat (ties and zeros included) on a 9 x 7 map, windows of 1 to 12
// pixels (wider than the map too) around every pixel, so that a window
// reaches beyond every side and corner of the map.
TEST(ChannelsTest, HeatFoldFoldsAsTheWholeMapDoes) {
  Grid<std::uint8_t> occupancy(9, 7, 1.0, 0);
  occupancy(4, 3) = 1;
  Grid<float> heat(9, 7, 1.0, 0.0f);
  std::uint64_t state = 12345;
  for (float& h : heat.data()) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const int draw = static_cast<int>((state >> 33) % 7);
    h = draw < 2 ? 0.0f : 0.125f * static_cast<float>(draw);  // ties
  }
  heat(0, 0) = 2.0f;  // a corner's own peak
  HeatFold fold;
  fold.Build(heat);
  ASSERT_EQ(fold.heat(), &heat);
  int windows = 0;
  for (int w : {1, 2, 3, 4, 5, 12}) {
    ChannelRenderer r(occupancy, {9.0, 7.0}, Params(ChannelFrame::kCentred, w));
    std::vector<float> direct(r.ImageSize()), folded(r.ImageSize());
    for (int y = 0; y < 7; ++y)
      for (int x = 0; x < 9; ++x) {
        const Vec2 self(x + 0.5, y + 0.5);
        r.RenderWithHeat(self, {}, heat, nullptr, nullptr, 0.01, direct.data());
        r.RenderWithHeat(self, {}, heat, nullptr, nullptr, 0.01, folded.data(),
                         {}, &fold);
        EXPECT_EQ(folded, direct) << "window " << w << " at " << x << "," << y;
        ++windows;
      }
  }
  EXPECT_EQ(windows, 6 * 63);
  // A fold built from another heatmap is not used.
  Grid<float> other = heat;
  other(8, 6) = 9.0f;
  ChannelRenderer r(occupancy, {9.0, 7.0}, Params(ChannelFrame::kCentred, 3));
  std::vector<float> direct(r.ImageSize()), folded(r.ImageSize());
  r.RenderWithHeat({0.5, 0.5}, {}, other, nullptr, nullptr, 0.01,
                   direct.data());
  r.RenderWithHeat({0.5, 0.5}, {}, other, nullptr, nullptr, 0.01, folded.data(),
                   {}, &fold);
  EXPECT_EQ(folded, direct);
  EXPECT_FLOAT_EQ(direct[3 * 9 + 8], 9.0f);  // heat's top-right corner pixel
}

// A robot's heatmap as edits of the base (TeamHeatmap::Edits) folds as the
// edited map itself does, made cell by cell: stamps that overlap, that are
// taken away and added in turn (some cells end a rounding below zero), at
// the map's edges and rows apart, under windows of 1 to 12 pixels around
// every pixel (so edited rows fall in the window, above and below it).
TEST(ChannelsTest, HeatFoldOfEditsFoldsAsTheEditedMapDoes) {
  const int nx = 11, ny = 13;
  Grid<std::uint8_t> occupancy(nx, ny, 1.0, 0);
  Grid<float> base(nx, ny, 1.0, 0.0f);
  std::uint64_t state = 777;
  const auto draw = [&](int n) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<int>((state >> 33) % n);
  };
  for (float& h : base.data()) h = 0.1f * static_cast<float>(draw(9));
  // Stamps: a rectangle of x0, y0, nx, ny with values in [0.05, 0.5].
  const auto stamp = [&](int x0, int y0, int sx, int sy) {
    HeatStamp st;
    st.x0 = x0, st.y0 = y0, st.nx = sx, st.ny = sy;
    for (int i = 0; i < sx * sy; ++i)
      st.values.push_back(0.05f * static_cast<float>(1 + draw(10)));
    return st;
  };
  const std::vector<HeatStamp> stamps = {
      stamp(0, 0, 4, 3), stamp(2, 1, 5, 4),   stamp(7, 10, 4, 3),
      stamp(3, 6, 1, 1), stamp(0, 12, 11, 1), stamp(5, 4, 6, 2)};
  // Take each stamp away where the base holds it, and add another.
  Grid<float> with = base;
  for (const HeatStamp& st : stamps) AddHeatStamp(st, false, &with);
  std::vector<HeatEdit> edits;
  for (std::size_t i = 0; i < stamps.size(); ++i) {
    edits.push_back({&stamps[i], true});
    edits.push_back({&stamps[(i + 2) % stamps.size()], false});
  }
  Grid<float> edited = with;
  for (const HeatEdit& e : edits) AddHeatStamp(*e.stamp, e.subtract, &edited);
  HeatFold fold_with;
  fold_with.Build(with);
  int windows = 0;
  for (int w : {1, 2, 3, 5, 8, 12}) {
    ChannelRenderer r(occupancy,
                      {static_cast<double>(nx), static_cast<double>(ny)},
                      Params(ChannelFrame::kCentred, w));
    std::vector<float> direct(r.ImageSize()), by_edits(r.ImageSize());
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        const Vec2 self(x + 0.5, y + 0.5);
        r.RenderWithHeat(self, {}, edited, nullptr, nullptr, 0.01,
                         direct.data());
        r.RenderWithHeat(self, {}, with, nullptr, nullptr, 0.01,
                         by_edits.data(), {}, &fold_with, &edits);
        EXPECT_EQ(by_edits, direct)
            << "window " << w << " at " << x << "," << y;
        ++windows;
      }
  }
  EXPECT_EQ(windows, 6 * nx * ny);
  // No edits: the base's own fold.
  ChannelRenderer r(occupancy,
                    {static_cast<double>(nx), static_cast<double>(ny)},
                    Params(ChannelFrame::kCentred, 5));
  std::vector<float> direct(r.ImageSize()), none(r.ImageSize());
  const std::vector<HeatEdit> no_edits;
  r.RenderWithHeat({5.5, 6.5}, {}, with, nullptr, nullptr, 0.01, direct.data());
  r.RenderWithHeat({5.5, 6.5}, {}, with, nullptr, nullptr, 0.01, none.data(),
                   {}, &fold_with, &no_edits);
  EXPECT_EQ(none, direct);
}

TEST(ChannelsTest, LocalizedTargetsLeaveNoHeat) {
  TinyWorld t;
  t.targets[0].log_det = std::log(t.eps);  // det Sigma = eps
  ChannelRenderer r(t.occupancy, t.size, Params(ChannelFrame::kGlobal));
  std::vector<float> img(r.ImageSize());
  r.Render(t.self, t.neighbours, t.targets, t.log_det_prior, t.eps, img.data());
  for (int i = 12; i < 16; ++i) EXPECT_EQ(img[i], 0.0f);
}

// A 4 x 3 m workspace, pixels and lattice steps of 1 m (every lattice point
// at a pixel centre), a thin wall at x = 2 from y = 0 to 2: the door is the
// top row. gamma = exp(-1 / L), L = 5 m.
struct WalledWorld {
  Map map{{4.0, 3.0}, {Box{{1.95, 0.0}, {2.05, 2.0}}}, 0.1, 1.0, 0.1};
  ChannelParams params = Params(ChannelFrame::kGlobal);
  Grid<float> heat{4, 3, 1.0, 0.0f};
  std::vector<double> log_det_prior{std::log(100.0), std::log(100.0)};
  double eps = 0.01;
  WalledWorld() {
    params.geodesic = true;
    params.geodesic_length = 5.0;
    params.observe_range = 1.0;
  }
  // A target at `mean` with det Sigma = det: weight log(det / eps) /
  // log(100 / eps).
  static HeatSource Target(const Vec2& mean, double det) {
    HeatSource t;
    t.mean = mean;
    t.cov = Mat2::Identity() * std::sqrt(det);
    t.log_det = std::log(det);
    return t;
  }
};

// A target at pixel (2, 0), just right of the wall: its observation pixels
// (within 1 m, seeing the mean) are (2, 0), (3, 0) and (2, 1); (1, 0) is 1 m
// off but behind the wall. The channel holds gamma^d, d the moves to the
// nearest of them round the wall through the door.
TEST(ChannelsTest, ReachGoesRoundAWallThroughItsDoor) {
  WalledWorld t;
  t.log_det_prior.resize(1);
  const std::vector<HeatSource> targets = {
      WalledWorld::Target({2.5, 0.5}, 1.0)};
  ChannelRenderer r(t.map.occupancy(), t.map.size(), t.params,
                    &t.map.lattice());
  ASSERT_EQ(r.channels(), 5);
  ASSERT_EQ(r.width(), 4);
  ASSERT_EQ(r.height(), 3);
  std::vector<float> img(r.ImageSize(), -1.0f);
  r.RenderWithHeat({0.5, 0.5}, {}, t.heat, &targets, &t.log_det_prior, t.eps,
                   img.data());
  const int moves[3][4] = {{5, 4, 0, 0}, {4, 3, 0, 1}, {3, 2, 1, 2}};
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x)
      EXPECT_NEAR(At(img, 3, 4, 4, x, y), std::pow(std::exp(-0.2), moves[y][x]),
                  1e-6)
          << x << ", " << y;
  // The heat channel is the heat as given.
  EXPECT_EQ(At(img, 3, 4, 3, 3, 0), 0.0f);
  // Render() projects the same belief: the same heat channel (3).
  std::vector<float> again(r.ImageSize());
  r.Render({0.5, 0.5}, {}, targets, t.log_det_prior, t.eps, again.data());
  for (int i = 4 * 12; i < 5 * 12; ++i) EXPECT_EQ(again[i], img[i]) << i;
}

// The wall closed (no door): a target on each side, weights 0.5 (left) and
// 0.25 (right); the channel is scaled by its largest value, each side sees
// its own target only, and a localized target (det <= eps) counts nothing.
TEST(ChannelsTest, ReachIsScaledToOneAndWallsSeparateTargets) {
  WalledWorld t;
  t.map = Map({4.0, 3.0}, {Box{{1.95, 0.0}, {2.05, 3.0}}}, 0.1, 1.0, 0.1);
  const std::vector<HeatSource> targets = {
      WalledWorld::Target({0.5, 2.5}, 1.0),   // w = 0.5
      WalledWorld::Target({3.5, 0.5}, 0.1)};  // w = log(10) / log(1e4) = 0.25
  ChannelRenderer r(t.map.occupancy(), t.map.size(), t.params,
                    &t.map.lattice());
  std::vector<float> img(r.ImageSize());
  r.RenderWithHeat({0.5, 0.5}, {}, t.heat, &targets, &t.log_det_prior, t.eps,
                   img.data());
  const double g = std::exp(-0.2);
  EXPECT_FLOAT_EQ(At(img, 3, 4, 4, 0, 2), 1.0f);  // 0.5 / 0.5
  EXPECT_FLOAT_EQ(At(img, 3, 4, 4, 1, 2), 1.0f);  // observes it too
  EXPECT_NEAR(At(img, 3, 4, 4, 1, 0), g * g, 1e-6);
  EXPECT_NEAR(At(img, 3, 4, 4, 3, 0), 0.5, 1e-6);          // 0.25 / 0.5
  EXPECT_NEAR(At(img, 3, 4, 4, 2, 2), 0.5 * g * g, 1e-6);  // via (2, 1)
  std::vector<HeatSource> localized = targets;
  localized[0].log_det = std::log(t.eps);
  r.RenderWithHeat({0.5, 0.5}, {}, t.heat, &localized, &t.log_det_prior, t.eps,
                   img.data());
  EXPECT_FLOAT_EQ(At(img, 3, 4, 4, 3, 0), 1.0f);  // now the largest
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 2; ++x) EXPECT_EQ(At(img, 3, 4, 4, x, y), 0.0f);
}

// A centred 3 x 3 window at the left end of an 8 x 3 m corridor, a wall at
// x = 3 with a door in the top row, a target at (6.5, 0.5) beyond the
// window. Alone, the window folds the target onto its border pixel (2, 0),
// straight through the wall; computed over 5 pixels around the window, the
// way through the door makes (2, 2) the window's highest pixel.
TEST(ChannelsTest, ReachOverAMarginSeesTheWayRoundBeyondTheWindow) {
  WalledWorld t;
  t.map = Map({8.0, 3.0}, {Box{{2.95, 0.0}, {3.05, 2.0}}}, 0.1, 1.0, 0.1);
  t.params.frame = ChannelFrame::kCentred;
  t.params.window = 3;
  t.heat = Grid<float>(8, 3, 1.0, 0.0f);
  t.log_det_prior.resize(1);
  const std::vector<HeatSource> targets = {
      WalledWorld::Target({6.5, 0.5}, 1.0)};
  const auto render = [&](int margin) {
    ChannelParams p = t.params;
    p.reach_margin = margin;
    ChannelRenderer r(t.map.occupancy(), t.map.size(), p, &t.map.lattice());
    std::vector<float> img(r.ImageSize());
    r.RenderWithHeat({1.5, 1.5}, {}, t.heat, &targets, &t.log_det_prior, t.eps,
                     img.data());
    return std::vector<float>(img.begin() + 4 * 9, img.end());
  };
  const double g = std::exp(-0.2);
  const std::vector<float> alone = render(0), wide = render(5);
  // Pixel (u, v) is index v * 3 + u; gamma^(moves from the highest pixel).
  for (int v = 0; v < 3; ++v)
    for (int u = 0; u < 3; ++u) {
      EXPECT_NEAR(alone[v * 3 + u], std::pow(g, (2 - u) + v), 1e-6)
          << u << ", " << v;
      EXPECT_NEAR(wide[v * 3 + u], std::pow(g, (2 - u) + (2 - v)), 1e-6)
          << u << ", " << v;
    }
}

// The same corridor with the reach channel over the whole workspace: the
// window's values are gamma^(moves to the observation pixels, through the
// door) scaled at the robot's own pixel (1, 1), which holds exp(-2): pixel
// (u, v) is u + v - 2 moves nearer, e^-2 gamma^(2 - u - v); and in log
// space nothing fades: a target 200 moves away gives the same window.
TEST(ChannelsTest, ReachOverTheWorldSeesTheWayRoundHoweverFar) {
  WalledWorld t;
  t.params.frame = ChannelFrame::kCentred;
  t.params.window = 3;
  t.params.reach_world = true;
  t.log_det_prior.resize(1);
  const double g = std::exp(-0.2);
  for (const double length : {8.0, 208.0}) {
    t.map = Map({length, 3.0}, {Box{{2.95, 0.0}, {3.05, 2.0}}}, 0.1, 1.0, 0.1);
    t.heat = Grid<float>(static_cast<int>(length), 3, 1.0, 0.0f);
    const std::vector<HeatSource> targets = {
        WalledWorld::Target({length - 1.5, 0.5}, 1.0)};
    ChannelRenderer r(t.map.occupancy(), t.map.size(), t.params,
                      &t.map.lattice());
    std::vector<float> img(r.ImageSize());
    r.RenderWithHeat({1.5, 1.5}, {}, t.heat, &targets, &t.log_det_prior, t.eps,
                     img.data());
    for (int v = 0; v < 3; ++v)
      for (int u = 0; u < 3; ++u)
        EXPECT_NEAR(img[4 * 9 + v * 3 + u],
                    std::exp(-2.0) * std::pow(g, 2 - u - v), 1e-6)
            << length << ": " << u << ", " << v;
  }
}

// With search points, channel 4 leads to the observation pixels of each
// point instead of the mean's: a target believed at (3.5, 0.5), right of
// the closed wall, whose search points are (0.5, 2.5) and (0.5, 0.5) on the
// left. Without them the left side holds nothing (no way round); with them
// each left pixel is gamma^(moves to the nearer point's pixels, within 1 m).
TEST(ChannelsTest, ReachLeadsToTheSearchPoints) {
  WalledWorld t;
  t.map = Map({4.0, 3.0}, {Box{{1.95, 0.0}, {2.05, 3.0}}}, 0.1, 1.0, 0.1);
  t.params.reach_world = true;
  t.params.search = true;
  t.log_det_prior.resize(1);
  const std::vector<HeatSource> targets = {
      WalledWorld::Target({3.5, 0.5}, 1.0)};
  ChannelRenderer r(t.map.occupancy(), t.map.size(), t.params,
                    &t.map.lattice());
  std::vector<float> img(r.ImageSize());
  r.RenderWithHeat({0.5, 0.5}, {}, t.heat, &targets, &t.log_det_prior, t.eps,
                   img.data());
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 2; ++x) EXPECT_EQ(At(img, 3, 4, 4, x, y), 0.0f);
  const SearchPointSets search = {{Vec2(0.5, 2.5), Vec2(0.5, 0.5)}};
  r.RenderWithHeat({0.5, 0.5}, {}, t.heat, &targets, &t.log_det_prior, t.eps,
                   img.data(), RobotMemory{&search});
  const double g = std::exp(-0.2);
  // Observation pixels: those within 1 m of a point, (0, *) and (1, 0),
  // (1, 2); (1, 1) is one move from them. The robot stands on one: exp(-2).
  const int moves[3][2] = {{0, 0}, {0, 1}, {0, 0}};
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 2; ++x)
      EXPECT_NEAR(At(img, 3, 4, 4, x, y),
                  std::exp(-2.0) * std::pow(g, moves[y][x]), 1e-6)
          << x << ", " << y;
  for (int y = 0; y < 3; ++y)
    for (int x = 2; x < 4; ++x) EXPECT_EQ(At(img, 3, 4, 4, x, y), 0.0f);
}

// The reach channel as the robot sees it (ChannelParams::reach_detour): in
// the walled world (wall at x = 2 up to y = 2, the door in the top row) a
// robot at pixel (1, 0) reaches the pixels right of the wall only round
// through the door. Pixel (2, 0) is 5 moves away against 1 straight on: a
// detour of 4; (2, 1) and (3, 1) detours of 2, (3, 0) of 4; the door's
// row and the left side none. Each pixel keeps its value times exp(-detour
// cell / D). Behind a closed wall, where the way leads only there (the
// search points of the target are beyond it), nothing is reachable: 0.
TEST(ChannelsTest, ReachDimmedByTheDetourFromTheRobot) {
  WalledWorld t;
  t.params.reach_world = true;
  t.log_det_prior.resize(1);
  const std::vector<HeatSource> targets = {
      WalledWorld::Target({3.5, 0.5}, 1.0)};
  const auto render = [&](double detour, const SearchPointSets* search) {
    ChannelParams p = t.params;
    p.reach_detour = detour;
    p.search = search != nullptr;
    ChannelRenderer r(t.map.occupancy(), t.map.size(), p, &t.map.lattice());
    std::vector<float> img(r.ImageSize());
    r.RenderWithHeat({1.5, 0.5}, {}, t.heat, &targets, &t.log_det_prior, t.eps,
                     img.data(), RobotMemory{search});
    return img;
  };
  const std::vector<float> plain = render(0.0, nullptr);
  const std::vector<float> seen = render(2.0, nullptr);
  const int detour[3][4] = {{0, 0, 4, 4}, {0, 0, 2, 2}, {0, 0, 0, 0}};
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) {
      ASSERT_GT(At(plain, 3, 4, 4, x, y), 0.0f) << x << ", " << y;
      EXPECT_NEAR(At(seen, 3, 4, 4, x, y),
                  At(plain, 3, 4, 4, x, y) * std::exp(-detour[y][x] * 0.5),
                  1e-6)
          << x << ", " << y;
    }
  // The other channels are the same.
  for (int i = 0; i < 4 * 12; ++i) EXPECT_EQ(seen[i], plain[i]) << i;
  t.map = Map({4.0, 3.0}, {Box{{1.95, 0.0}, {2.05, 3.0}}}, 0.1, 1.0, 0.1);
  const SearchPointSets beyond = {{Vec2(3.5, 2.5)}};
  const std::vector<float> closed_plain = render(0.0, &beyond);
  const std::vector<float> closed = render(2.0, &beyond);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) {
      if (x >= 2) EXPECT_GT(At(closed_plain, 3, 4, 4, x, y), 0.0f);
      EXPECT_EQ(At(closed, 3, 4, 4, x, y),
                x < 2 ? At(closed_plain, 3, 4, 4, x, y) : 0.0f)
          << x << ", " << y;
    }
}

// The broad reach channel (ChannelParams::reach_broad) is the last one,
// after the trail: channel 4 again at decay length reach_broad and without
// the detour, from the same sources. So it equals channel 4 of a renderer
// whose L is reach_broad and whose detour is off, pixel for pixel, and the
// channels before it are those of a renderer without it. In the walled
// world the way to the target behind the wall goes round through the door.
TEST(ChannelsTest, BroadReachIsReachAtItsLengthWithoutTheDetour) {
  WalledWorld t;
  t.params.reach_world = true;
  t.params.trail = true;
  t.log_det_prior.resize(1);
  const std::vector<HeatSource> targets = {
      WalledWorld::Target({3.5, 0.5}, 1.0)};
  RobotMemory memory;
  memory.moved = true;
  memory.came_from = {0.5, 0.5};
  const auto render = [&](double length, double detour, double broad) {
    ChannelParams p = t.params;
    p.geodesic_length = length;
    p.reach_detour = detour;
    p.reach_broad = broad;
    ChannelRenderer r(t.map.occupancy(), t.map.size(), p, &t.map.lattice());
    std::vector<float> img(r.ImageSize());
    r.RenderWithHeat({1.5, 0.5}, {}, t.heat, &targets, &t.log_det_prior, t.eps,
                     img.data(), memory);
    return img;
  };
  const std::size_t plane = 12;
  const std::vector<float> with = render(0.25, 0.5, 5.0);
  const std::vector<float> without = render(0.25, 0.5, 0.0);
  const std::vector<float> at_five = render(5.0, 0.0, 0.0);
  ASSERT_EQ(with.size(), 7 * plane);
  ASSERT_EQ(without.size(), 6 * plane);
  for (std::size_t i = 0; i < 6 * plane; ++i) EXPECT_EQ(with[i], without[i]);
  EXPECT_EQ(with[5 * plane + 0], 1.0f);  // the trail stays channel 5
  int lit = 0;
  for (std::size_t i = 0; i < plane; ++i) {
    EXPECT_EQ(with[6 * plane + i], at_five[4 * plane + i]) << i;
    lit += with[6 * plane + i] > 0.0f;
  }
  // Every pixel is on a way to the target (the door is open): none is 0,
  // and the broad channel differs from the sharp one.
  EXPECT_EQ(lit, 12);
  EXPECT_NE(with[6 * plane + 8], with[4 * plane + 8]);
}

// The second reach channel (ChannelParams::reach_second), worked by hand in
// a corridor of 8 pixels, 1 m each, targets of equal weight at pixels 0 and
// 7 (observation range 0.5 m: each target's own pixel alone), L = 1 m, the
// robot at pixel 2. Channel 4 is exp(2 - min(x, 7 - x) - 2) capped at 1;
// the second channel holds the farther target's cost, max(x, 7 - x), so it
// reads exp(5 - max(x, 7 - x) - 2): rising from the robot toward pixel 7
// up to the middle, where pixel 7's target becomes the nearer. Channel 4
// and the channels before it are those of a renderer without it. With one
// target, or two search points of one target, there is no second target:
// the channel is 0.
TEST(ChannelsTest, SecondReachLeadsToEachPixelsSecondTarget) {
  const Map corridor({8.0, 1.0}, {}, 0.1, 1.0, 0.1);
  ChannelParams params = Params(ChannelFrame::kGlobal);
  params.geodesic = true;
  params.geodesic_length = 1.0;
  params.observe_range = 0.5;
  params.reach_world = true;
  params.search = true;
  Grid<float> heat(8, 1, 1.0, 0.0f);
  const std::vector<HeatSource> two = {WalledWorld::Target({0.5, 0.5}, 1.0),
                                       WalledWorld::Target({7.5, 0.5}, 1.0)};
  const std::vector<double> prior(2, std::log(100.0));
  const auto render = [&](bool second, const std::vector<HeatSource>& targets,
                          const SearchPointSets* search) {
    ChannelParams p = params;
    p.reach_second = second;
    ChannelRenderer r(corridor.occupancy(), corridor.size(), p,
                      &corridor.lattice());
    std::vector<float> img(r.ImageSize(), -1.0f);
    r.RenderWithHeat({2.5, 0.5}, {}, heat, &targets, &prior, 0.01, img.data(),
                     RobotMemory{search});
    return img;
  };
  const std::vector<float> with = render(true, two, nullptr);
  const std::vector<float> without = render(false, two, nullptr);
  ASSERT_EQ(with.size(), 6u * 8);
  ASSERT_EQ(without.size(), 5u * 8);
  for (std::size_t i = 0; i < without.size(); ++i)
    EXPECT_EQ(with[i], without[i]) << i;
  for (int x = 0; x < 8; ++x) {
    EXPECT_NEAR(At(with, 1, 8, 4, x, 0),
                std::min(1.0, std::exp(-std::min(x, 7 - x))), 1e-6)
        << x;
    EXPECT_NEAR(At(with, 1, 8, 5, x, 0), std::exp(3.0 - std::max(x, 7 - x)),
                1e-6)
        << x;
  }
  // One target, then one target's two search points (pixels 0 and 7): no
  // second target anywhere.
  const std::vector<HeatSource> one = {two[0]};
  const SearchPointSets ends = {{Vec2(0.5, 0.5), Vec2(7.5, 0.5)}};
  for (const SearchPointSets* search :
       {static_cast<const SearchPointSets*>(nullptr), &ends}) {
    const std::vector<float> alone = render(true, one, search);
    for (int x = 0; x < 8; ++x) EXPECT_EQ(At(alone, 1, 8, 5, x, 0), 0.0f) << x;
    EXPECT_GT(At(alone, 1, 8, 4, 7, 0), 0.0f);
  }
}

// The observation pixels a renderer keeps per point change nothing: robots
// rendered on a renderer that has seen their targets' points before (and
// from two threads at once) get the images of a fresh renderer, with the
// reach over the window and over the world, in a cluttered 12 m world.
TEST(ChannelsTest, KeptObservationPixelsGiveAFreshRenderersImages) {
  std::vector<Box> boxes;
  for (int i = 0; i < 12; ++i)
    boxes.push_back(Box::FromCenterSize(
        Vec2(1.0 + (i * 7) % 10, 1.0 + (i * 5) % 10), Vec2(0.6, 1.2)));
  const Map map({12.0, 12.0}, boxes, 0.1, 0.5, 0.15);
  std::vector<HeatSource> targets;
  for (int k = 0; k < 6; ++k)  // pairs on one x: points told apart by y
    targets.push_back(WalledWorld::Target({0.7 + 3.8 * (k / 2), 11.3 - 1.7 * k},
                                          0.5 + 0.1 * k));
  const std::vector<double> prior(targets.size(), std::log(100.0));
  const std::vector<Vec2> robots = {{0.75, 0.75}, {6.25, 5.75}, {11.25, 2.25}};
  for (const bool world : {false, true}) {
    const ChannelParams params = ReachParams(16, 5.0, world);
    const ChannelRenderer warm(map.occupancy(), map.size(), params,
                               &map.lattice());
    const Grid<float> heat = MakeHeatmapGrid(map.size(), params.cell);
    const auto render = [&](const ChannelRenderer& r, const Vec2& self) {
      std::vector<float> img(r.ImageSize());
      r.RenderWithHeat(self, {}, heat, &targets, &prior, 0.01, img.data());
      return img;
    };
    for (const Vec2& self : robots) render(warm, self);  // the cache filled
    std::vector<std::vector<float>> threaded(robots.size());
    std::vector<std::thread> threads;
    for (std::size_t i = 0; i < robots.size(); ++i)
      threads.emplace_back([&, i] { threaded[i] = render(warm, robots[i]); });
    for (std::thread& t : threads) t.join();
    for (std::size_t i = 0; i < robots.size(); ++i) {
      const ChannelRenderer fresh(map.occupancy(), map.size(), params,
                                  &map.lattice());
      const std::vector<float> expected = render(fresh, robots[i]);
      EXPECT_EQ(render(warm, robots[i]), expected) << world << " " << i;
      EXPECT_EQ(threaded[i], expected) << world << " " << i;
      // The reach channel holds something: the test can tell a wrong one.
      const std::size_t plane = expected.size() / params.num_channels();
      EXPECT_GT(*std::max_element(expected.begin() + 4 * plane,
                                  expected.begin() + 5 * plane),
                0.0f);
    }
  }
}

// The reach channel over the workspace searches only toward the window's
// pixels and the robot's (A*, targets entering by a bound): its images are
// bit for bit those of a search by cost alone from every target
// (internal::ExhaustiveReachWorld), in random cluttered worlds of 40 x 30
// m, with robots in the open, inside boxes and at the border, targets
// localized or not, with and without search points, the second channel and
// the detour, a sharp and a broad L, and windows that cover the workspace.
TEST(ChannelsTest, BoundedReachOverTheWorldIsTheExhaustiveSearch) {
  std::mt19937 rng(20261206);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  int lit = 0, compared = 0;
  for (int world = 0; world < 6; ++world) {
    std::vector<Box> boxes;
    for (int i = 0; i < 40; ++i)
      boxes.push_back(Box::FromCenterSize(
          Vec2(40.0 * u01(rng), 30.0 * u01(rng)),
          Vec2(0.3 + 3.0 * u01(rng), 0.3 + 3.0 * u01(rng))));
    const Map map({40.0, 30.0}, boxes, 0.1, 0.5, 0.15);
    std::vector<HeatSource> targets;
    SearchPointSets search;
    const int count = 1 + world * 7;
    for (int k = 0; k < count; ++k) {
      // det from 1e-3 (below eps: weight 0, not a source) to 100.
      targets.push_back(
          WalledWorld::Target({40.0 * u01(rng), 30.0 * u01(rng)},
                              std::pow(10.0, -3.0 + 5.0 * u01(rng))));
      std::vector<Vec2> points;
      if (k % 3 == 1)
        for (int a = 0; a < 1 + k % 4; ++a)
          points.emplace_back(40.0 * u01(rng), 30.0 * u01(rng));
      search.push_back(points);
    }
    const std::vector<double> prior(targets.size(), std::log(100.0));
    std::vector<Vec2> robots = {{0.25, 0.25}, {39.75, 29.75}};
    for (int i = 0; i < 8; ++i)
      robots.emplace_back(40.0 * u01(rng), 30.0 * u01(rng));
    for (const Box& b : boxes) {  // one inside a box
      robots.push_back(b.Center());
      break;
    }
    for (int variant = 0; variant < 4; ++variant) {
      ChannelParams params = ReachParams(40, variant == 1 ? 5.0 : 0.25, true);
      if (variant == 3) params.frame = ChannelFrame::kGlobal;
      params.search = variant != 2;
      params.reach_detour = variant == 0 ? 0.5 : 0.0;
      params.reach_second = variant == 2;
      params.reach_broad = variant == 1 ? 2.0 : 0.0;
      const ChannelRenderer r(map.occupancy(), map.size(), params,
                              &map.lattice());
      const ChannelRenderer reference = internal::ExhaustiveReachWorld(r);
      const Grid<float> heat = MakeHeatmapGrid(map.size(), params.cell);
      const std::size_t plane = r.ImageSize() / params.num_channels();
      for (const Vec2& self : robots) {
        std::vector<float> bounded(r.ImageSize(), -1.0f);
        std::vector<float> exhaustive(r.ImageSize(), -2.0f);
        r.RenderWithHeat(self, {}, heat, &targets, &prior, 0.01, bounded.data(),
                         RobotMemory{&search});
        reference.RenderWithHeat(self, {}, heat, &targets, &prior, 0.01,
                                 exhaustive.data(), RobotMemory{&search});
        const auto differ =
            std::mismatch(bounded.begin(), bounded.end(), exhaustive.begin());
        ASSERT_TRUE(differ.first == bounded.end())
            << "world " << world << " variant " << variant << " robot ("
            << self.x() << ", " << self.y() << "): value "
            << differ.first - bounded.begin() << " is " << *differ.first
            << ", not " << *differ.second;
        ++compared;
        lit += *std::max_element(bounded.begin() + 4 * plane,
                                 bounded.begin() + 5 * plane) > 0.0f;
      }
    }
  }
  // Most images hold a way: the comparison can tell a wrong one.
  EXPECT_GT(lit, compared / 2) << lit << " of " << compared;
}

// A model sees a world through pixels of its lattice step (AtLatticeStep):
// the same world twice as large at twice the step, every length of it
// doubled (boxes, robots, targets, covariances, and the heat's blur and
// the observation range, which stay in metres; eps and the priors' det by
// 16, so that the weights keep), gives the images of the world at the
// model's own step, pixel for pixel, the reach channel over the workspace
// with its detour included. At the model's own step the parameters are
// the model's.
TEST(ChannelsTest, AWorldAtTwiceTheStepLooksTheSameTwiceAsLarge) {
  ChannelParams model = ReachParams(16, 0.25, true);
  model.reach_detour = 0.5;
  const ChannelParams same = AtLatticeStep(model, 0.5);
  EXPECT_EQ(same.cell, 0.5);
  EXPECT_EQ(same.geodesic_length, 0.25);
  EXPECT_EQ(same.reach_detour, 0.5);
  std::vector<Box> boxes, doubled;
  for (int i = 0; i < 10; ++i) {
    boxes.push_back(Box::FromCenterSize(
        Vec2(1.0 + (i * 7) % 10, 1.0 + (i * 5) % 10), Vec2(0.6, 1.2)));
    doubled.push_back(Box{2.0 * boxes.back().lo, 2.0 * boxes.back().hi});
  }
  const Map small({12.0, 12.0}, boxes, 0.1, 0.5, 0.15);
  const Map large({24.0, 24.0}, doubled, 0.2, 1.0, 0.3);
  std::vector<HeatSource> targets, targets2;
  for (int k = 0; k < 5; ++k) {
    HeatSource t = WalledWorld::Target({0.7 + 2.3 * k, 11.3 - 2.1 * k},
                                       std::pow(10.0, -1.0 + 0.5 * k));
    targets.push_back(t);
    t.mean *= 2.0;
    t.cov *= 4.0;
    t.log_det += std::log(16.0);
    targets2.push_back(t);
  }
  const std::vector<double> prior(5, std::log(100.0)),
      prior2(5, std::log(1600.0));
  ChannelParams model2 = model;  // the world's own lengths, doubled
  model2.blur *= 2.0;
  model2.observe_range *= 2.0;
  const ChannelParams at_step = AtLatticeStep(model2, 1.0);
  EXPECT_EQ(at_step.cell, 1.0);
  EXPECT_EQ(at_step.geodesic_length, 0.5);
  EXPECT_EQ(at_step.reach_detour, 1.0);
  ChannelRenderer r(small.occupancy(), small.size(), model, &small.lattice());
  ChannelRenderer r2(large.occupancy(), large.size(), at_step,
                     &large.lattice());
  ASSERT_EQ(r.ImageSize(), r2.ImageSize());
  for (const Vec2& self :
       {Vec2(0.75, 0.75), Vec2(6.25, 5.75), Vec2(11.25, 2.25)}) {
    const std::vector<Vec2> neighbours = {self + Vec2(1.0, 0.5)};
    std::vector<float> img(r.ImageSize()), img2(r2.ImageSize());
    r.Render(self, neighbours, targets, prior, 0.01, img.data());
    r2.Render(2.0 * self, {2.0 * neighbours[0]}, targets2, prior2, 0.16,
              img2.data());
    const std::size_t plane = img.size() / model.num_channels();
    for (std::size_t i = 0; i < img.size(); ++i)
      ASSERT_NEAR(img2[i], img[i], 1e-5)
          << "channel " << i / plane << " pixel " << i % plane << " robot "
          << self.transpose();
    EXPECT_GT(*std::max_element(img.begin() + 4 * plane, img.end()), 0.0f);
  }
}

// The observation pixels lie within the sensor's range: a model's 2 m is cut
// to a 0.5 m sensor's, and kept with a 3 m sensor (its own standoff).
TEST(ChannelsTest, ObservationRangeIsCutToTheSensors) {
  ChannelParams p = Params(ChannelFrame::kCentred, 40);
  p.observe_range = 2.0;
  EXPECT_EQ(AtSensorRange(p, 0.5).observe_range, 0.5);
  EXPECT_EQ(AtSensorRange(p, 3.0).observe_range, 2.0);
  EXPECT_EQ(AtSensorRange(p, 2.0).observe_range, 2.0);
  EXPECT_EQ(AtSensorRange(p, 0.5).cell, p.cell);
}

// A workspace whose grids at the channels' cell would pass
// kMaxChannelPixels is refused with the numbers (a 10 km world at 0.5 m:
// 20 GB); read at its own lattice step of 10 m it fits.
TEST(ChannelsTest, GridsPastTheLimitAreRefusedWithTheirSize) {
  ChannelParams p = Params(ChannelFrame::kCentred, 40);
  p.cell = 0.5;
  const std::string why = ChannelGridProblem(Vec2(10000.0, 10000.0), p);
  EXPECT_NE(why.find("the channels' grids cover the workspace [10000, "
                     "10000] at their 0.5 m cell: 20000 x 20000 pixels"),
            std::string::npos)
      << why;
  EXPECT_EQ(ChannelGridProblem(Vec2(10000.0, 10000.0), AtLatticeStep(p, 10.0)),
            "");
  EXPECT_EQ(ChannelGridProblem(Vec2(100.0, 100.0), p), "");
}

// The trail channel (the last): in a centred 3 x 3 window of 1 m pixels at
// (0.25, 1.75), the robot came from 1 m south: pixel (1, 0) holds 1 and no
// other; before its first move, none.
TEST(ChannelsTest, TrailMarksWhereTheRobotCameFrom) {
  TinyWorld t;
  ChannelParams p = Params(ChannelFrame::kCentred);
  p.trail = true;
  ChannelRenderer r(t.occupancy, t.size, p);
  ASSERT_EQ(r.channels(), 5);
  std::vector<float> img(r.ImageSize());
  const auto trail = [&](const RobotMemory& m) {
    r.Render(t.self, t.neighbours, t.targets, t.log_det_prior, t.eps,
             img.data(), m);
    return std::vector<float>(img.begin() + 4 * 9, img.end());
  };
  RobotMemory came;
  came.moved = true;
  came.came_from = t.self - Vec2(0.0, 1.0);
  std::vector<float> expected(9, 0.0f);
  expected[0 * 3 + 1] = 1.0f;
  EXPECT_EQ(trail(came), expected);
  EXPECT_EQ(trail(RobotMemory{}), std::vector<float>(9, 0.0f));
}

// SetTrail, as the policy and aia.Mission.channels fill the trail: on a
// 4 x 2 lattice of 1 m steps, a robot at (2.5, 1.5) whose last move was
// right came from (1.5, 1.5), one that moved up from (2.5, 0.5); no move,
// or a move the lattice could not have made into this point (down into the
// top row from beyond it), leaves no trail.
TEST(ChannelsTest, SetTrailIsThePointTheLastMoveCameFrom) {
  const Lattice lattice(Vec2(4.0, 2.0), 1.0, 0.1, {});
  const int here = lattice.Index(2, 1);
  RobotMemory m;
  SetTrail(lattice, here, Move::kRight, &m);
  EXPECT_TRUE(m.moved);
  EXPECT_EQ(m.came_from, Vec2(1.5, 1.5));
  SetTrail(lattice, here, Move::kUp, &m);
  EXPECT_TRUE(m.moved);
  EXPECT_EQ(m.came_from, Vec2(2.5, 0.5));
  SetTrail(lattice, here, Move::kStay, &m);
  EXPECT_FALSE(m.moved);
  SetTrail(lattice, here, Move::kDown, &m);
  EXPECT_FALSE(m.moved);
}

// Declared names (core/fields.h): "centered" reads as "centred", which is
// the name written.
TEST(ChannelsTest, FrameNamesParse) {
  ChannelFrame f = ChannelFrame::kGlobal;
  EXPECT_TRUE(ParseEnumName("centred", &f));
  EXPECT_EQ(f, ChannelFrame::kCentred);
  EXPECT_TRUE(ParseEnumName("global", &f));
  EXPECT_EQ(f, ChannelFrame::kGlobal);
  EXPECT_TRUE(ParseEnumName("centered", &f));
  EXPECT_STREQ(EnumNameOf(f), "centred");
  EXPECT_FALSE(ParseEnumName("local", &f));
  EXPECT_EQ(f, ChannelFrame::kCentred);
}

}  // namespace
}  // namespace aia
