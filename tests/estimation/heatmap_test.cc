// The heatmap (docs/rendering.md, The heatmap) against values worked out by
// hand.
#include "aia/estimation/heatmap.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <thread>

namespace aia {
namespace {

// One static 2-D target, prior N(mu0, Sigma0), whose belief row 0 is set to
// N(mu, Sigma) directly in information form.
struct OneTarget {
  BeliefLayout layout{std::vector<TargetModel>(1)};
  BeliefSet beliefs{&layout, 1};
  void Set(const Vec2& mu, const Mat2& sigma) {
    const Mat2 omega = sigma.inverse();
    beliefs.Omega(0, 0) = omega;
    beliefs.Xi(0, 0) = omega * mu;
  }
};

TEST(HeatWeightTest, ByHand) {
  const double eps = 0.01;
  const double prior = std::log(1.0);  // det Sigma0 = 1
  // log(0.1 / 0.01) / log(1 / 0.01) = 1 / 2.
  EXPECT_NEAR(HeatWeight(std::log(0.1), prior, eps), 0.5, 1e-12);
  EXPECT_NEAR(HeatWeight(std::log(1.0), prior, eps), 1.0, 1e-12);  // unexplored
  EXPECT_NEAR(HeatWeight(std::log(3.0), prior, eps), 1.0,
              1e-12);  // worse than the prior
  EXPECT_EQ(HeatWeight(std::log(0.01), prior, eps), 0.0);  // at eps
  EXPECT_EQ(HeatWeight(std::log(1e-5), prior, eps), 0.0);  // localized
  // A prior already at or below eps: all or nothing.
  EXPECT_EQ(HeatWeight(std::log(0.02), std::log(0.005), eps), 1.0);
  EXPECT_EQ(HeatWeight(std::log(0.002), std::log(0.005), eps), 0.0);
}

TEST(HeatmapTest, MakeHeatmapGridCoversTheWorkspace) {
  const Grid<float> g = MakeHeatmapGrid({20.0, 10.0}, 0.1);
  EXPECT_EQ(g.nx(), 200);
  EXPECT_EQ(g.ny(), 100);
  EXPECT_EQ(MakeHeatmapGrid({20.0, 10.05}, 0.1).ny(), 101);
  for (float v : g.data()) ASSERT_EQ(v, 0.0f);
}

TEST(HeatmapTest, SingleTargetCellValuesByHand) {
  OneTarget t;
  // mu at the centre of cell (10, 10) of a 0.5 m grid; Sigma = diag(0.5, 0.2):
  // det 0.1, so with eps = 0.01 and det Sigma0 = 1 the weight is 1/2; with
  // s = 1, Sigma + s^2 I = diag(1.5, 1.2).
  t.Set({5.25, 5.25}, Vec2(0.5, 0.2).asDiagonal());
  HeatmapParams params;
  params.eps = 0.01;
  params.blur = 1.0;
  Grid<float> grid(20, 20, 0.5);
  ProjectHeatmap(t.beliefs, 0, {0.0}, params, &grid);
  EXPECT_NEAR(grid(10, 10), 0.5, 1e-6);
  EXPECT_NEAR(grid(12, 10), 0.5 * std::exp(-0.5 * 1.0 / 1.5),
              1e-6);  // 1 m in x: 0.358266
  EXPECT_NEAR(grid(10, 11), 0.5 * std::exp(-0.5 * 0.25 / 1.2),
              1e-6);  // 0.5 m in y: 0.450538
  EXPECT_NEAR(grid(8, 12), 0.5 * std::exp(-0.5 * (1.0 / 1.5 + 1.0 / 1.2)),
              1e-6);
  // Symmetric about the mean.
  EXPECT_FLOAT_EQ(grid(8, 10), grid(12, 10));
  EXPECT_FLOAT_EQ(grid(10, 7), grid(10, 13));
}

TEST(HeatmapTest, CorrelatedCovarianceByHand) {
  OneTarget t;
  Mat2 sigma;
  sigma << 0.5, 0.3, 0.3, 0.5;  // det 0.16
  t.Set({5.25, 5.25}, sigma);
  HeatmapParams params;
  params.eps = 0.01;
  params.blur = 1.0;
  Grid<float> grid(20, 20, 0.5);
  ProjectHeatmap(t.beliefs, 0, {std::log(0.16)}, params,
                 &grid);  // the prior: weight 1
  // S = [[1.5, 0.3], [0.3, 1.5]], det 2.16, S^-1 = [[1.5, -0.3], [-0.3, 1.5]]
  // / 2.16. d = (1, 1): d' S^-1 d = 2.4 / 2.16; d = (1, -1): 3.6 / 2.16.
  EXPECT_NEAR(grid(10, 10), 1.0, 1e-6);
  EXPECT_NEAR(grid(12, 12), std::exp(-0.5 * 2.4 / 2.16), 1e-6);
  EXPECT_NEAR(grid(12, 8), std::exp(-0.5 * 3.6 / 2.16), 1e-6);
  EXPECT_GT(grid(12, 12), grid(12, 8));  // heat stretches along the correlation
}

TEST(HeatmapTest, LocalizedTargetLeavesNoHeat) {
  OneTarget t;
  t.Set({5.0, 5.0}, 0.01 * Mat2::Identity());  // det 1e-4 <= eps 1e-3
  HeatmapParams params;
  params.eps = 1e-3;
  Grid<float> grid(20, 20, 0.5, 7.0f);  // stale values are overwritten
  ProjectHeatmap(t.beliefs, 0, {0.0}, params, &grid);
  for (float v : grid.data()) ASSERT_EQ(v, 0.0f);
}

TEST(HeatmapTest, UnexploredTargetHasFullWeightAtItsMean) {
  OneTarget t;
  const Mat2 prior = Mat2::Identity();
  t.Set({3.25, 6.75}, prior);  // still the prior
  HeatmapParams params;
  params.eps = 0.1;
  params.blur = 1.0;
  Grid<float> grid(20, 20, 0.5);
  ProjectHeatmap(t.beliefs, 0, {std::log(prior.determinant())}, params, &grid);
  EXPECT_NEAR(grid(6, 13), 1.0, 1e-6);
  float peak = 0.0f;
  for (float v : grid.data()) peak = std::max(peak, v);
  EXPECT_NEAR(peak, 1.0f, 1e-6);
}

TEST(HeatmapTest, CutOffWindowAndTargetsAdd) {
  OneTarget t;
  t.Set({2.25, 2.25}, 0.25 * Mat2::Identity());
  HeatmapParams params;
  params.eps = 0.001;
  params.blur = 0.5;  // S = 0.5 I: sigma 0.707 m, cut-off at 4 sigma = 2.83 m
  Grid<float> grid(40, 40, 0.25);
  ProjectHeatmap(t.beliefs, 0, {std::log(0.0625)}, params, &grid);
  for (int iy = 0; iy < grid.ny(); ++iy)
    for (int ix = 0; ix < grid.nx(); ++ix) {
      const double d = (grid.CellCenter(ix, iy) - Vec2(2.25, 2.25)).norm();
      const double exact = std::exp(-0.5 * d * d / 0.5);
      if (d > 2.9)
        ASSERT_EQ(grid(ix, iy), 0.0f) << ix << "," << iy;
      else if (d < 2.8)
        ASSERT_NEAR(grid(ix, iy), exact, 1e-6) << ix << "," << iy;
    }
  // Two Gaussians add.
  Grid<float> twice(40, 40, 0.25);
  AddGaussianHeat({2.25, 2.25}, 0.25 * Mat2::Identity(), 1.0, 0.5, 4.0, &twice);
  AddGaussianHeat({2.25, 2.25}, 0.25 * Mat2::Identity(), 0.5, 0.5, 4.0, &twice);
  EXPECT_NEAR(twice(8, 8), 1.5 * grid(8, 8), 1e-6);
  // A mean far outside the grid touches nothing.
  AddGaussianHeat({-100.0, 500.0}, Mat2::Identity(), 1.0, 0.5, 4.0, &twice);
  EXPECT_NEAR(twice(8, 8), 1.5 * grid(8, 8), 1e-6);
}

TEST(HeatmapTest, FourDimensionalTargetUsesThePositionMarginal) {
  const TargetModel model = TargetModel::Static(4);
  BeliefLayout layout({model});
  BeliefSet beliefs(&layout, 1);
  Eigen::Matrix4d sigma = Eigen::Matrix4d::Identity();
  sigma(0, 2) = sigma(2, 0) = 0.5;  // position x correlated with velocity x
  Eigen::Vector4d mu(5.25, 5.25, 1.0, 0.0);
  beliefs.Omega(0, 0) = sigma.inverse();
  beliefs.Xi(0, 0) = sigma.inverse() * mu;
  HeatmapParams params;
  params.eps = 1e-3;
  params.blur = 1.0;
  Grid<float> grid(20, 20, 0.5);
  ProjectHeatmap(beliefs, 0, {std::log(sigma.determinant())}, params, &grid);
  // Position marginal I: S = 2 I. 1 m in x: exp(-1/4).
  EXPECT_NEAR(grid(10, 10), 1.0, 1e-6);
  EXPECT_NEAR(grid(12, 10), std::exp(-0.25), 1e-6);
}

TEST(HeatmapTest, ReusesTheGridWithoutAllocating) {
  OneTarget t;
  t.Set({5.0, 5.0}, Mat2::Identity());
  HeatmapParams params;
  Grid<float> grid(200, 200, 0.1);
  const float* storage = grid.data().data();
  for (int i = 0; i < 3; ++i)
    ProjectHeatmap(t.beliefs, 0, {0.0}, params, &grid);
  EXPECT_EQ(grid.data().data(), storage);
  EXPECT_EQ(grid.size(), 200u * 200u);
}

// Eight robots, six static targets: every robot holds the prior of targets 0
// to 3 but for robot 2 (target 1) and robots 5 and 6 (target 3, one
// measurement each); targets 4 and 5 have no majority belief (every robot's
// differs), and target 0's copies differ by float rounding only.
struct Team {
  BeliefLayout layout{std::vector<TargetModel>(6)};
  BeliefSet beliefs{&layout, 8};
  std::vector<double> prior;
  Team() {
    std::vector<Eigen::VectorXd> means;
    std::vector<Eigen::MatrixXd> covs;
    for (int k = 0; k < 6; ++k) {
      means.push_back(Vec2(2.0 + 3.0 * k, 4.0 + 2.0 * k));
      covs.push_back(Eigen::MatrixXd::Identity(2, 2));
      prior.push_back(0.0);
    }
    beliefs.SetPrior(means, covs);
    beliefs.Omega(0, 0)(0, 0) = std::nextafter(1.0, 0.0);  // a rounded copy
    Measure(2, 1, 40.0);
    Measure(5, 3, 10.0);
    Measure(6, 3, 20.0);
    for (int i = 0; i < 8; ++i) {
      Measure(i, 4, 1.0 + i);
      Measure(i, 5, 0.5 * (i + 1));
    }
  }
  void Measure(int robot, int k, double precision) {
    beliefs.Omega(robot, k) += precision * Mat2::Identity();
    beliefs.Xi(robot, k) +=
        precision * (beliefs.PositionMean(robot, k) + Vec2(0.3, -0.2));
  }
};

TEST(TeamHeatmapTest, EachRobotsHeatmapIsItsOwnToFloatRounding) {
  Team t;
  HeatmapParams params;
  params.eps = 0.01;
  const Grid<float> shape(60, 60, 0.5);
  TeamHeatmap team;
  const std::vector<int> rows = {0, 1, 2, 3, 4, 5, 6, 7};
  team.Prepare(t.beliefs, rows, t.prior, params, shape);
  // Own stamps: robot 2's target 1, robots 5 and 6's target 3, and all
  // eight robots' targets 4 and 5; target 0's rounded copy is the majority's.
  EXPECT_EQ(team.own_stamps(), 1 + 2 + 16);
  for (int b = 0; b < 8; ++b) {
    Grid<float> scratch = shape, want = shape;
    const Grid<float>& got = team.Robot(b, &scratch);
    ProjectHeatmap(t.beliefs, b, t.prior, params, &want);
    for (std::size_t c = 0; c < got.size(); ++c)
      ASSERT_NEAR(got.data()[c], want.data()[c], 1e-6) << "robot " << b;
  }
}

TEST(TeamHeatmapTest, ASubsetOfTargetsIsTheHeatOfThoseTargetsAlone) {
  Team t;
  HeatmapParams params;
  params.eps = 0.01;
  const Grid<float> shape(60, 60, 0.5);
  TeamHeatmap team;
  team.Prepare(t.beliefs, {0, 1, 2, 3, 4, 5, 6, 7}, t.prior, params, shape);
  // Targets 1 and 3 (robots 2, 5 and 6 hold their own beliefs of them),
  // target 4 (every robot its own), none.
  for (const std::vector<std::uint8_t>& keep :
       {std::vector<std::uint8_t>{0, 1, 0, 1, 0, 0},
        std::vector<std::uint8_t>{0, 0, 0, 0, 1, 0},
        std::vector<std::uint8_t>{0, 0, 0, 0, 0, 0}}) {
    for (int b = 0; b < 8; ++b) {
      std::vector<HeatSource> sources, kept;
      std::vector<double> prior;
      HeatSources(t.beliefs, b, &sources);
      for (int k = 0; k < 6; ++k)
        if (keep[k]) {
          kept.push_back(sources[k]);
          prior.push_back(t.prior[k]);
        }
      Grid<float> scratch = shape, want = shape;
      const Grid<float>& got = team.Robot(b, keep, &scratch);
      ProjectHeatmap(kept, prior, params, &want);
      for (std::size_t c = 0; c < got.size(); ++c)
        ASSERT_NEAR(got.data()[c], want.data()[c], 1e-6) << "robot " << b;
    }
  }
  // Every target kept: the robot's whole heatmap.
  Grid<float> scratch = shape, whole = shape;
  const Grid<float>& all =
      team.Robot(2, std::vector<std::uint8_t>(6, 1), &scratch);
  const Grid<float>& base = team.Robot(2, &whole);
  for (std::size_t c = 0; c < all.size(); ++c)
    ASSERT_NEAR(all.data()[c], base.data()[c], 1e-6);
}

TEST(TeamHeatmapTest, RelabellingTheRobotsPermutesTheHeatmaps) {
  Team t;
  HeatmapParams params;
  params.eps = 0.01;
  const Grid<float> shape(60, 60, 0.5);
  TeamHeatmap a, b;
  a.Prepare(t.beliefs, {0, 1, 2, 3, 4, 5, 6, 7}, t.prior, params, shape);
  const std::vector<int> perm = {5, 2, 7, 0, 6, 1, 3, 4};
  b.Prepare(t.beliefs, perm, t.prior, params, shape);
  for (int k = 0; k < 8; ++k) {
    Grid<float> sx = shape, sy = shape;
    const Grid<float>& x = a.Robot(perm[k], &sx);
    const Grid<float>& y = b.Robot(k, &sy);
    ASSERT_EQ(x.data(), y.data()) << "robot " << perm[k];
  }
}

// A layout of wider blocks built where the last one was (the same address)
// gets scratch of its own width: the heat is a fresh TeamHeatmap's.
TEST(TeamHeatmapTest, ANewLayoutAtTheSameAddressIsReadWhole) {
  HeatmapParams params;
  params.eps = 0.01;
  const Grid<float> shape(20, 20, 0.5);
  BeliefLayout layout({TargetModel::Static(2)});
  TeamHeatmap reused;
  {
    BeliefSet one(&layout, 3);
    one.SetPrior({Eigen::Vector2d(5, 5)}, {Eigen::MatrixXd::Identity(2, 2)});
    reused.Prepare(one, {0, 1, 2}, {0.0}, params, shape);
  }
  layout = BeliefLayout(std::vector<TargetModel>(3, TargetModel::Static(4)));
  BeliefSet wide(&layout, 3);
  wide.SetPrior(
      std::vector<Eigen::VectorXd>({Eigen::Vector4d(2, 3, 0, 0),
                                    Eigen::Vector4d(5, 5, 0, 0),
                                    Eigen::Vector4d(8, 6, 0, 0)}),
      std::vector<Eigen::MatrixXd>(3, Eigen::MatrixXd::Identity(4, 4)));
  const std::vector<double> prior(3, 0.0);
  reused.Prepare(wide, {0, 1, 2}, prior, params, shape);
  TeamHeatmap fresh;
  fresh.Prepare(wide, {0, 1, 2}, prior, params, shape);
  EXPECT_EQ(reused.base().data(), fresh.base().data());
}

TEST(TeamHeatmapTest, ThreadsDoNotChangeTheHeatmaps) {
  Team t;
  HeatmapParams params;
  params.eps = 0.01;
  const Grid<float> shape(60, 60, 0.5);
  const std::vector<int> rows = {0, 1, 2, 3, 4, 5, 6, 7};
  TeamHeatmap serial, threaded;
  serial.Prepare(t.beliefs, rows, t.prior, params, shape);
  // Three workers, the work split unevenly between them.
  const RangeRunner three = [](int n, const RangeTask& f) {
    std::vector<std::thread> pool;
    const int cut[4] = {0, n / 5, n / 2, n};
    for (int w = 0; w < 3; ++w) pool.emplace_back(f, cut[w], cut[w + 1], w);
    for (std::thread& th : pool) th.join();
  };
  threaded.Prepare(t.beliefs, rows, t.prior, params, shape, three, 3);
  EXPECT_EQ(serial.own_stamps(), threaded.own_stamps());
  for (int b = 0; b < 8; ++b) {
    Grid<float> sa = shape, sb = shape;
    ASSERT_EQ(serial.Robot(b, &sa).data(), threaded.Robot(b, &sb).data());
  }
}

// Forty targets, 2-D and 4-D, over twelve robots: the keys are made a tile
// of targets at a time, so targets on both sides of a tile's edge and a
// split that cuts through tiles must each still give every robot its own
// heatmap, the same with threads as without.
TEST(TeamHeatmapTest, ManyTargetsAcrossTilesAreEachRobotsOwn) {
  const int m = 40, n = 12;
  std::vector<TargetModel> models;
  std::vector<Eigen::VectorXd> means;
  std::vector<Eigen::MatrixXd> covs;
  std::vector<double> prior;
  for (int k = 0; k < m; ++k) {
    const int d = k % 7 == 3 ? 4 : 2;
    models.push_back(TargetModel::Static(d));
    Eigen::VectorXd mean = Eigen::VectorXd::Zero(d);
    mean.head<2>() = Vec2(1.0 + 0.7 * k, 2.0 + 0.6 * (k % 9));
    means.push_back(mean);
    covs.push_back(Eigen::MatrixXd::Identity(d, d));
    prior.push_back(0.0);
  }
  const BeliefLayout layout(models);
  BeliefSet beliefs(&layout, n);
  beliefs.SetPrior(means, covs);
  // Most rows hold the prior; robot i measures the targets k with (k + i)
  // % 11 == 0 (runs of equal rows broken at several places per target),
  // and target 17 differs in every row.
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < m; ++k)
      if ((k + i) % 11 == 0 || k == 17) {
        const double r = 2.0 + i + 0.1 * k;
        beliefs.Omega(i, k).topLeftCorner<2, 2>() += r * Mat2::Identity();
        beliefs.Xi(i, k).head<2>() +=
            r * (beliefs.PositionMean(i, k) + Vec2(0.2, 0.1 * i));
      }
  HeatmapParams params;
  params.eps = 0.01;
  const Grid<float> shape(70, 40, 0.5);
  std::vector<int> rows(n);
  for (int i = 0; i < n; ++i) rows[i] = i;
  TeamHeatmap serial, threaded;
  serial.Prepare(beliefs, rows, prior, params, shape);
  const RangeRunner three = [](int count, const RangeTask& f) {
    std::vector<std::thread> pool;
    // Over the 40 targets: 0-6, 7-22, 23-39, through the tiles of 16.
    const int cut[4] = {0, count * 7 / 40, count * 23 / 40, count};
    for (int w = 0; w < 3; ++w) pool.emplace_back(f, cut[w], cut[w + 1], w);
    for (std::thread& th : pool) th.join();
  };
  threaded.Prepare(beliefs, rows, prior, params, shape, three, 3);
  EXPECT_EQ(serial.own_stamps(), threaded.own_stamps());
  for (int b = 0; b < n; ++b) {
    Grid<float> sa = shape, sb = shape, want = shape;
    const Grid<float>& got = serial.Robot(b, &sa);
    ASSERT_EQ(got.data(), threaded.Robot(b, &sb).data()) << "robot " << b;
    ProjectHeatmap(beliefs, b, prior, params, &want);
    for (std::size_t c = 0; c < got.size(); ++c)
      ASSERT_NEAR(got.data()[c], want.data()[c], 1e-6) << "robot " << b;
  }
}

}  // namespace
}  // namespace aia
