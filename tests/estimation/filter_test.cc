#include "aia/estimation/filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "aia/core/rng.h"
#include "aia/core/thread_pool.h"
#include "aia/estimation/belief.h"
#include "aia/estimation/sensor_model.h"

namespace aia {
namespace {

using Graph = std::vector<std::vector<int>>;
using Measurements = std::vector<std::vector<Measurement>>;

TargetModel StaticModel(int dim) { return TargetModel::Static(dim); }

// Constant velocity, state (px, py, vx, vy), unit time step, noise q I.
TargetModel ConstantVelocity(double q) {
  TargetModel m = StaticModel(4);
  m.A(0, 2) = 1.0;
  m.A(1, 3) = 1.0;
  m.q = q;
  return m;
}

Eigen::MatrixXd RandomSpd(int dim, Rng* rng) {
  Eigen::MatrixXd a(dim, dim);
  for (int i = 0; i < a.size(); ++i) a.data()[i] = rng->Normal();
  return a * a.transpose() + 0.5 * Eigen::MatrixXd::Identity(dim, dim);
}

// Independent random SPD blocks and xi in every row.
void Randomize(BeliefSet* beliefs, Rng* rng) {
  const BeliefLayout& layout = beliefs->layout();
  for (int r = 0; r < beliefs->rows(); ++r) {
    for (int k = 0; k < layout.num_targets(); ++k) {
      beliefs->Omega(r, k) = RandomSpd(layout.dim(k), rng);
      for (int d = 0; d < layout.dim(k); ++d)
        beliefs->Xi(r, k)(d) = rng->Normal();
    }
  }
}

// Directed graph: j in N_i with probability `density`.
Graph RandomGraph(int n, double density, Rng* rng) {
  Graph g(n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      if (j != i && rng->Bernoulli(density)) g[i].push_back(j);
    }
  }
  return g;
}

Graph FullGraph(int n) {
  Graph g(n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      if (j != i) g[i].push_back(j);
    }
  }
  return g;
}

Measurements RandomMeasurements(int n, int num_targets, Rng* rng) {
  Measurements z(n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < num_targets; ++k) {
      if (rng->Bernoulli(0.5)) {
        z[i].push_back(
            {k, Vec2(rng->Normal(), rng->Normal()), rng->Uniform(1.0, 100.0)});
      }
    }
  }
  return z;
}

std::vector<Vec2> RandomPositions(int n, Rng* rng) {
  std::vector<Vec2> p(n);
  for (Vec2& q : p) q = Vec2(rng->Uniform(0.0, 10.0), rng->Uniform(0.0, 10.0));
  return p;
}

double MaxRelDiff(const BeliefSet::Storage& a, const BeliefSet::Storage& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

// ---------------------------------------------------------------------------
// Single filter steps against hand-worked values.

TEST(FilterTest, MeasurementUpdateByHand) {
  const BeliefLayout layout({StaticModel(2)});
  BeliefSet beliefs(&layout, 1);
  beliefs.SetPrior({Eigen::Vector2d(0.0, 0.0)}, {Eigen::Matrix2d::Identity()});
  // r = 1 / 0.5^2 = 4, y + p = (1, 2) + (1, 1) = (2, 3):
  //   Omega = I + 4 I = 5 I,  xi = 0 + 4 (2, 3) = (8, 12),
  //   mu = xi / 5 = (1.6, 2.4),  det Sigma = 1 / 25.
  AddMeasurements({{0, Vec2(1.0, 2.0), 4.0}}, Vec2(1.0, 1.0), &beliefs, 0);
  EXPECT_TRUE(
      beliefs.Omega(0, 0).isApprox(5.0 * Eigen::Matrix2d::Identity(), 1e-15));
  EXPECT_TRUE(beliefs.Xi(0, 0).isApprox(Eigen::Vector2d(8.0, 12.0), 1e-15));
  EXPECT_TRUE(beliefs.PositionMean(0, 0).isApprox(Vec2(1.6, 2.4), 1e-14));
  EXPECT_NEAR(beliefs.DetCovariance(0, 0), 1.0 / 25.0, 1e-15);
  EXPECT_NEAR(beliefs.LogDetCovariance(0, 0), -std::log(25.0), 1e-14);
}

TEST(FilterTest, MeasurementOfAMovingTargetTouchesOnlyThePosition) {
  const BeliefLayout layout({ConstantVelocity(0.1)});
  BeliefSet beliefs(&layout, 1);
  beliefs.SetPrior({Eigen::Vector4d(0.0, 0.0, 1.0, 2.0)},
                   {Eigen::Matrix4d::Identity()});
  AddMeasurements({{0, Vec2(1.0, 2.0), 4.0}}, Vec2(1.0, 1.0), &beliefs, 0);
  // Z = M' R^-1 M with M = [I 0]: only the (px, py) diagonal grows.
  Eigen::Matrix4d omega = Eigen::Matrix4d::Identity();
  omega(0, 0) = omega(1, 1) = 5.0;
  EXPECT_TRUE(beliefs.Omega(0, 0).isApprox(omega, 1e-15));
  EXPECT_TRUE(
      beliefs.Xi(0, 0).isApprox(Eigen::Vector4d(8.0, 12.0, 1.0, 2.0), 1e-15));
}

TEST(FilterTest, PredictTwoDimensionalDriftByHand) {
  TargetModel m = StaticModel(2);
  m.A << 1.0, 1.0, 0.0, 1.0;
  m.b << 0.5, -1.0;
  m.q = 1.0;
  const BeliefLayout layout({m});
  BeliefSet beliefs(&layout, 2);
  // Sigma = diag(1, 2), mu = (1, 2)  ->  Omega = diag(1, 0.5), xi = (1, 1).
  beliefs.SetPrior({Eigen::Vector2d(1.0, 2.0)},
                   {Eigen::Vector2d(1.0, 2.0).asDiagonal()});
  Predict(&beliefs);
  // A Sigma A' = [1 1; 0 1] diag(1, 2) [1 0; 1 1] = [3 2; 2 2];  + Q = [4 2; 2
  // 3], det = 8, so Omega' = [3 -2; -2 4] / 8 = [0.375 -0.25; -0.25 0.5]. mu' =
  // A mu + b = (3, 2) + (0.5, -1) = (3.5, 1), xi' = Omega' mu' = (1.3125 -
  // 0.25, -0.875 + 0.5) = (1.0625, -0.375).
  Eigen::Matrix2d omega;
  omega << 0.375, -0.25, -0.25, 0.5;
  for (int r = 0; r < 2; ++r) {
    EXPECT_TRUE(beliefs.Omega(r, 0).isApprox(omega, 1e-14));
    EXPECT_TRUE(
        beliefs.Xi(r, 0).isApprox(Eigen::Vector2d(1.0625, -0.375), 1e-14));
    EXPECT_TRUE(beliefs.PositionMean(r, 0).isApprox(Vec2(3.5, 1.0), 1e-14));
  }
}

TEST(FilterTest, PredictConstantVelocityByHand) {
  const BeliefLayout layout({ConstantVelocity(0.5)});
  BeliefSet beliefs(&layout, 1);
  beliefs.SetPrior({Eigen::Vector4d(0.0, 0.0, 1.0, 2.0)},
                   {Eigen::Matrix4d::Identity()});
  Predict(&beliefs);
  // Per axis (p, v): A = [1 1; 0 1], A A' = [2 1; 1 1], + q I =
  // [2.5 1; 1 1.5], det = 2.75, so Omega' = [1.5 -1; -1 2.5] / 2.75.
  // mu' = (0 + 1, 0 + 2, 1, 2); per axis xi' = Omega' (p, v):
  //   x: (1.5 - 1, -1 + 2.5) / 2.75 = (0.5, 1.5) / 2.75,
  //   y: (3 - 2, -2 + 5) / 2.75 = (1, 3) / 2.75.
  Eigen::Matrix4d omega = Eigen::Matrix4d::Zero();
  omega(0, 0) = omega(1, 1) = 1.5 / 2.75;
  omega(2, 2) = omega(3, 3) = 2.5 / 2.75;
  omega(0, 2) = omega(2, 0) = omega(1, 3) = omega(3, 1) = -1.0 / 2.75;
  EXPECT_TRUE(beliefs.Omega(0, 0).isApprox(omega, 1e-14));
  EXPECT_TRUE(beliefs.Xi(0, 0).isApprox(
      Eigen::Vector4d(0.5, 1.0, 1.5, 3.0) / 2.75, 1e-14));
  EXPECT_TRUE(
      beliefs.Mean(0, 0).isApprox(Eigen::Vector4d(1.0, 2.0, 1.0, 2.0), 1e-14));
  EXPECT_EQ(beliefs.Omega(0, 0), beliefs.Omega(0, 0).transpose());
}

// The DKF sums Omega blocks across robots every step, so prediction must hand
// back exactly symmetric blocks, not merely symmetric to rounding.
TEST(FilterTest, PredictKeepsOmegaExactlySymmetric) {
  Rng rng(2);
  TargetModel drift = StaticModel(2);
  drift.A << 0.9, 0.3, -0.2, 1.1;
  drift.q = 0.01;
  TargetModel cv = ConstantVelocity(0.05);
  cv.A(2, 0) = 0.1;  // no special structure
  const BeliefLayout layout({drift, cv});
  BeliefSet beliefs(&layout, 6);
  Randomize(&beliefs, &rng);
  for (int t = 0; t < 5; ++t) {
    Predict(&beliefs);
    for (int r = 0; r < beliefs.rows(); ++r) {
      for (int k = 0; k < layout.num_targets(); ++k) {
        const Eigen::MatrixXd omega = beliefs.Omega(r, k);
        EXPECT_EQ(omega, omega.transpose()) << "row " << r << " target " << k;
      }
    }
  }
}

TEST(FilterTest, PredictLeavesStaticTargetsBitForBit) {
  Rng rng(3);
  const BeliefLayout mixed(
      {StaticModel(2), ConstantVelocity(0.1), StaticModel(4)});
  BeliefSet beliefs(&mixed, 4);
  Randomize(&beliefs, &rng);
  const BeliefSet before = beliefs;
  Predict(&beliefs);
  for (int r = 0; r < beliefs.rows(); ++r) {
    for (int k : {0, 2}) {
      EXPECT_EQ(beliefs.Omega(r, k), before.Omega(r, k));
      EXPECT_EQ(beliefs.Xi(r, k), before.Xi(r, k));
    }
    EXPECT_NE(beliefs.Omega(r, 1), before.Omega(r, 1));
  }

  const BeliefLayout all_static({StaticModel(2), StaticModel(4)});
  BeliefSet still(&all_static, 3);
  Randomize(&still, &rng);
  const BeliefSet::Storage data = still.data();
  Predict(&still);
  EXPECT_EQ(still.data(), data);
}

// ---------------------------------------------------------------------------
// DKF weights and fusion.

TEST(FusionWeightsTest, ByHand) {
  // 0 hears {1, 2}; 1 hears {0}; 2 hears {0, 1, 3}; 3 is isolated.
  const Graph g = {{1, 2}, {0}, {0, 1, 3}, {}};
  Eigen::MatrixXd W(2, 7);
  FusionWeights(g, 0.75, &W);
  Eigen::MatrixXd expected(4, 4);
  const double third = 0.25 / 3.0;
  expected << 0.75, 0.125, 0.125, 0.0,  //
      0.25, 0.75, 0.0, 0.0,             //
      third, third, 0.75, third,        //
      0.0, 0.0, 0.0, 1.0;
  EXPECT_TRUE(W.isApprox(expected, 1e-15)) << W;
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(W.row(i).sum(), 1.0, 1e-15);

  // Same size again: the storage is reused and stale entries are cleared.
  const double* storage = W.data();
  FusionWeights({{}, {}, {}, {0}}, 0.75, &W);
  EXPECT_EQ(W.data(), storage);
  expected.setIdentity();
  expected(3, 3) = 0.75;
  expected(3, 0) = 0.25;
  EXPECT_EQ(W, expected);
}

TEST(FuseTest, TwoRobotsByHand) {
  const BeliefLayout layout({StaticModel(2)});
  BeliefSet predicted(&layout, 2);
  predicted.Omega(0, 0) = Eigen::Matrix2d::Identity();
  predicted.Omega(1, 0) = 3.0 * Eigen::Matrix2d::Identity();
  predicted.Xi(1, 0) = Eigen::Vector2d(3.0, 6.0);
  Eigen::MatrixXd W;
  FusionWeights({{1}, {0}}, 0.75, &W);
  BeliefSet fused;
  Fuse(predicted, W, {{{0, Vec2(1.0, 2.0), 4.0}}, {}},
       {Vec2(1.0, 1.0), Vec2(5.0, 5.0)}, &fused);
  // Robot 0: 0.75 I + 0.25 (3 I) + 4 I = 5.5 I;  xi = 0.25 (3, 6) + 4 (2, 3) =
  // (8.75, 13.5). Robot 1: 0.25 I + 0.75 (3 I) = 2.5 I;         xi = 0.75 (3,
  // 6) = (2.25, 4.5).
  EXPECT_TRUE(
      fused.Omega(0, 0).isApprox(5.5 * Eigen::Matrix2d::Identity(), 1e-15));
  EXPECT_TRUE(fused.Xi(0, 0).isApprox(Eigen::Vector2d(8.75, 13.5), 1e-15));
  EXPECT_TRUE(
      fused.Omega(1, 0).isApprox(2.5 * Eigen::Matrix2d::Identity(), 1e-15));
  EXPECT_TRUE(fused.Xi(1, 0).isApprox(Eigen::Vector2d(2.25, 4.5), 1e-15));
}

// The episode's weights without the N x N matrix give the matrix's numbers
// to the bit, on sparse and dense graphs (the sum trick) alike.
TEST(FuseTest, DkfWeightsGiveTheMatrixNumbersToTheBit) {
  Rng rng(8);
  const BeliefLayout layout({StaticModel(2), ConstantVelocity(0.1)});
  const int n = 23;
  BeliefSet predicted(&layout, n);
  const std::vector<Vec2> p = RandomPositions(n, &rng);
  for (const double density : {0.0, 0.05, 0.3, 0.55, 0.9, 1.0}) {
    Randomize(&predicted, &rng);
    const Graph g = RandomGraph(n, density, &rng);
    Eigen::MatrixXd W;
    FusionWeights(g, 0.75, &W);
    DkfWeights w;
    MakeDkfWeights(g, 0.75, &w);
    const Measurements z = RandomMeasurements(n, layout.num_targets(), &rng);
    BeliefSet dense, sparse;
    Fuse(predicted, W, z, p, &dense);
    Fuse(predicted, w, z, p, &sparse);
    EXPECT_EQ(dense.data(), sparse.data()) << "density " << density;
  }
}

// Splits for a RangeRunner: chunks of 7 indices handed to a pool's threads,
// and chunks of 5 run last to first on the calling thread.
RangeRunner PoolRunner(ThreadPool* pool) {
  return [pool](int count, const RangeTask& f) {
    pool->Run((count + 6) / 7, [&](int c, int worker) {
      f(7 * c, std::min(count, 7 * c + 7), worker);
    });
  };
}

RangeRunner Backwards() {
  return [](int count, const RangeTask& f) {
    for (int b = (count - 1) / 5 * 5; b >= 0; b -= 5)
      f(b, std::min(count, b + 5), 0);
  };
}

// A large team's fusion split over threads (the rows, and the column sum of
// the dense rows) gives the serial numbers to the bit, whatever the split;
// each row is reported once, after it is final.
TEST(FuseTest, SplitOverThreadsGivesTheSerialNumbersToTheBit) {
  Rng rng(11);
  std::vector<TargetModel> models;
  for (int k = 0; k < 150; ++k)
    models.push_back(k % 3 == 0 ? ConstantVelocity(0.1) : StaticModel(2));
  const BeliefLayout layout(models);
  const int n = 240;  // 240 x 1400 doubles: past the size that is split
  ASSERT_GE(static_cast<long>(n) * layout.stride(), 1L << 18);
  BeliefSet predicted(&layout, n);
  Randomize(&predicted, &rng);
  const std::vector<Vec2> p = RandomPositions(n, &rng);
  const Measurements z = RandomMeasurements(n, layout.num_targets(), &rng);
  ThreadPool pool(2);
  const RangeRunner threads = PoolRunner(&pool), backwards = Backwards();
  for (const double density : {0.1, 0.9, 1.0}) {
    const Graph g =
        density == 1.0 ? FullGraph(n) : RandomGraph(n, density, &rng);
    DkfWeights w;
    MakeDkfWeights(g, 0.75, &w);
    BeliefSet serial;
    Fuse(predicted, w, z, p, &serial);
    for (const RangeRunner* run : {&threads, &backwards}) {
      BeliefSet split;
      std::vector<std::atomic<int>> done(n);
      Fuse(predicted, w, z, p, &split, *run, [&](int i) {
        // Row i is final here: the same bits as the serial fusion's.
        EXPECT_EQ(split.data().row(i), serial.data().row(i));
        ++done[i];
      });
      // Random rows share nothing: row by row, whatever the graph.
      const bool shared = split.sharing();
      EXPECT_FALSE(shared);
      EXPECT_EQ(split.data(), serial.data()) << "density " << density;
      for (int i = 0; i < n; ++i)
        EXPECT_EQ(done[i].load(), shared ? 0 : 1) << i;
    }
  }
}

// The same with shared beliefs (a full graph, the team at one prior, some
// robots that measured): the mix target by target and the time update,
// split over threads or not, give the same bits and stay shared.
TEST(FuseTest, SharedSetsSplitOverThreadsGiveTheSerialNumbersToTheBit) {
  Rng rng(13);
  std::vector<TargetModel> models;
  for (int k = 0; k < 150; ++k)
    models.push_back(k % 3 == 0 ? ConstantVelocity(0.1) : StaticModel(2));
  const BeliefLayout layout(models);
  const int n = 240, m = layout.num_targets();
  std::vector<Eigen::VectorXd> means;
  std::vector<Eigen::MatrixXd> covs;
  for (int k = 0; k < m; ++k) {
    means.push_back(Eigen::VectorXd::Random(layout.dim(k)));
    covs.push_back(RandomSpd(layout.dim(k), &rng));
  }
  BeliefSet prior(&layout, n);
  prior.SetPrior(means, covs);
  const std::vector<Vec2> p = RandomPositions(n, &rng);
  Measurements z(n);
  for (int i = 0; i < n; i += 9)
    z[i].push_back({i % m, Vec2(rng.Normal(), rng.Normal()), 30.0});
  DkfWeights w;
  const Graph g = FullGraph(n);
  MakeDkfWeights(g, 0.75, &w);
  BeliefSet predicted;
  Fuse(prior, w, z, p, &predicted);
  ASSERT_TRUE(predicted.sharing());
  ThreadPool pool(2);
  const RangeRunner threads = PoolRunner(&pool), backwards = Backwards();
  BeliefSet serial;
  Fuse(predicted, w, z, p, &serial);
  BeliefSet serial_predicted = serial;
  Predict(&serial_predicted);
  ASSERT_TRUE(serial.sharing() && serial_predicted.sharing());
  for (const RangeRunner* run : {&threads, &backwards}) {
    BeliefSet split;
    Fuse(predicted, w, z, p, &split, *run);
    EXPECT_TRUE(split.sharing());
    EXPECT_TRUE(split.Materialized() == serial.Materialized());
    Predict(&split, nullptr, *run);
    EXPECT_TRUE(split.sharing());
    EXPECT_TRUE(split.Materialized() == serial_predicted.Materialized());
  }
}

// The time update split over threads: the serial numbers to the bit, and
// the serial error (the first failing block in row-major order; a target
// scaled back in every row).
TEST(FilterTest, PredictSplitOverThreadsGivesTheSerialNumbersAndErrors) {
  Rng rng(12);
  std::vector<TargetModel> models;
  for (int k = 0; k < 150; ++k) {
    TargetModel drift = StaticModel(2);
    drift.q = 0.01;
    models.push_back(k % 3 == 0   ? ConstantVelocity(0.1)
                     : k % 3 == 1 ? drift
                                  : StaticModel(2));
  }
  models[20].A *= 2.0;  // unstable
  const BeliefLayout layout(models);
  const int n = 240;
  ASSERT_GE(static_cast<long>(n) * layout.stride(), 1L << 18);
  BeliefSet start(&layout, n);
  Randomize(&start, &rng);
  ThreadPool pool(2);
  const RangeRunner threads = PoolRunner(&pool), backwards = Backwards();
  // What Predict throws on `b` with `run` ("" when nothing).
  auto error = [](BeliefSet b, const RangeRunner& run) -> std::string {
    try {
      Predict(&b, nullptr, run);
    } catch (const EstimateDiverged& e) {
      return std::to_string(e.target()) + ": " + e.what();
    }
    return "";
  };

  BeliefSet serial = start;
  Predict(&serial);
  for (const RangeRunner* run : {&threads, &backwards}) {
    BeliefSet split = start;
    Predict(&split, nullptr, *run);
    EXPECT_EQ(split.data(), serial.data());
  }

  // Two blocks that are not finite: the one first in row-major order.
  BeliefSet broken = start;
  broken.Omega(150, 3)(0, 0) = std::nan("");
  broken.Omega(30, 9)(1, 1) = std::nan("");
  const std::string first = error(broken, {});
  EXPECT_EQ(first.rfind("9: ", 0), 0u) << first;
  for (const RangeRunner* run : {&threads, &backwards})
    EXPECT_EQ(error(broken, *run), first);

  // The unstable target at a variance of 1e30 in every row: scaled back in
  // each, so it diverges; one row still below the bound keeps it.
  BeliefSet wide = start;
  for (int r = 0; r < n; ++r)
    wide.Omega(r, 20) = 1e-30 * Eigen::Matrix2d::Identity();
  EXPECT_EQ(error(wide, {}).rfind("20: ", 0), 0u);
  for (const RangeRunner* run : {&threads, &backwards})
    EXPECT_EQ(error(wide, *run), error(wide, {}));
  wide.Omega(n - 1, 20) = Eigen::Matrix2d::Identity();
  for (const RangeRunner* run : {&threads, &backwards})
    EXPECT_EQ(error(wide, *run), "");
}

// The time update of a shared set (common blocks predicted once) throws
// what the same rows unshared throw: the first failing block in row-major
// order (a common block's failure is its first holder's), and a target
// diverges where every active row was scaled back.
TEST(FilterTest, PredictOnASharedSetFailsAsOnItsRows) {
  Rng rng(14);
  std::vector<TargetModel> models;
  for (int k = 0; k < 30; ++k)
    models.push_back(k % 3 == 0 ? ConstantVelocity(0.1) : StaticModel(2));
  for (TargetModel& model : models) model.q = 0.01;
  models[20].A *= 2.0;  // unstable
  const BeliefLayout layout(models);
  const int n = 50, m = layout.num_targets();
  std::vector<Eigen::VectorXd> means;
  std::vector<Eigen::MatrixXd> covs;
  for (int k = 0; k < m; ++k) {
    means.push_back(Eigen::VectorXd::Random(layout.dim(k)));
    covs.push_back(RandomSpd(layout.dim(k), &rng));
  }
  BeliefSet start(&layout, n);
  start.SetPrior(means, covs);
  start.Omega(7, 3)(0, 0) += 1.0;  // a few blocks of their own
  start.Omega(2, 9)(0, 0) += 1.0;
  ASSERT_TRUE(start.sharing());
  ThreadPool pool(2);
  const RangeRunner threads = PoolRunner(&pool);
  auto error = [](BeliefSet b, const std::vector<std::uint8_t>* active,
                  const RangeRunner& run) -> std::string {
    try {
      Predict(&b, active, run);
    } catch (const EstimateDiverged& e) {
      return std::to_string(e.target()) + ": " + e.what();
    }
    return "";
  };
  auto unshared = [](BeliefSet b) {
    b.Unshare();
    return b;
  };
  auto expect_same = [&](const BeliefSet& b,
                         const std::vector<std::uint8_t>* active) {
    const std::string want = error(unshared(b), active, {});
    EXPECT_EQ(error(b, active, {}), want);
    EXPECT_EQ(error(b, active, threads), want);
    return want;
  };

  // A common block that is not finite (target 9, first held by row 0)
  // before an own one (row 7's block of target 3).
  BeliefSet broken = start;
  broken.CommonBlockToWrite(9)[0] = std::nan("");
  broken.Omega(7, 3)(0, 0) = std::nan("");
  EXPECT_EQ(expect_same(broken, nullptr).rfind("9: ", 0), 0u);
  // With row 0's own block of 9 (finite) the common one's first holder
  // is row 1: row 0's own failing block of 12 comes first.
  broken.Omega(0, 9)(0, 0) = 1.0;
  broken.Omega(0, 12)(0, 0) = std::nan("");
  EXPECT_EQ(expect_same(broken, nullptr).rfind("12: ", 0), 0u);

  // The unstable target far beyond the bound in every block: diverges;
  // one active row with its own block below it keeps it; inactive, not.
  BeliefSet wide = start;
  Eigen::Map<Eigen::Matrix2d>(wide.CommonBlockToWrite(20)) =
      1e-30 * Eigen::Matrix2d::Identity();
  EXPECT_EQ(expect_same(wide, nullptr).rfind("20: ", 0), 0u);
  wide.Omega(n - 1, 20) = Eigen::Matrix2d::Identity();
  EXPECT_EQ(expect_same(wide, nullptr), "");
  std::vector<std::uint8_t> active(n, 1);
  active[n - 1] = 0;
  EXPECT_EQ(expect_same(wide, &active).rfind("20: ", 0), 0u);

  // And the numbers where nothing fails.
  BeliefSet a = start, b = unshared(start);
  Predict(&a, nullptr, threads);
  Predict(&b);
  EXPECT_TRUE(a.sharing());
  EXPECT_TRUE(a.Materialized() == b.data());
}

// Fuse exploits the structure of W; it must still be exactly W * B + Z.
TEST(FuseTest, MatchesDenseProductOnAnyGraph) {
  Rng rng(5);
  const BeliefLayout layout(
      {StaticModel(2), ConstantVelocity(0.1), StaticModel(2)});
  const int n = 17;
  BeliefSet predicted(&layout, n);
  BeliefSet fused(&layout, n);
  const std::vector<Vec2> p = RandomPositions(n, &rng);
  for (const double density : {0.0, 0.1, 0.45, 0.55, 0.8, 0.95, 1.0, -1.0}) {
    Randomize(&predicted, &rng);
    Eigen::MatrixXd W;
    if (density >= 0.0) {
      FusionWeights(RandomGraph(n, density, &rng), 0.75, &W);
    } else {
      // Unequal weights in every row: the general path.
      W.resize(n, n);
      for (int i = 0; i < W.size(); ++i) W.data()[i] = rng.Uniform();
      for (int i = 0; i < n; ++i) W.row(i) /= W.row(i).sum();
    }
    const Measurements z = RandomMeasurements(n, layout.num_targets(), &rng);
    Fuse(predicted, W, z, p, &fused);

    BeliefSet expected(&layout, n);
    expected.data() = W * predicted.data();
    for (int i = 0; i < n; ++i) AddMeasurements(z[i], p[i], &expected, i);
    EXPECT_LT(MaxRelDiff(fused.data(), expected.data()), 1e-14)
        << "density " << density;
  }
}

TEST(FuseTest, CommutesWithRelabellingTheRobots) {
  Rng rng(7);
  const BeliefLayout layout(
      {StaticModel(2), ConstantVelocity(0.1), StaticModel(2)});
  const int n = 12;
  for (const double density : {0.3, 0.7, 1.0}) {
    BeliefSet predicted(&layout, n);
    Randomize(&predicted, &rng);
    const Graph g = RandomGraph(n, density, &rng);
    const Measurements z = RandomMeasurements(n, layout.num_targets(), &rng);
    const std::vector<Vec2> p = RandomPositions(n, &rng);

    // Robot i becomes robot perm[i].
    std::vector<int> perm(n);
    std::iota(perm.begin(), perm.end(), 0);
    for (int i = n - 1; i > 0; --i)
      std::swap(perm[i], perm[rng.UniformInt(i + 1)]);
    BeliefSet predicted_pi(&layout, n);
    Graph g_pi(n);
    Measurements z_pi(n);
    std::vector<Vec2> p_pi(n);
    for (int i = 0; i < n; ++i) {
      predicted_pi.CopyRow(perm[i], predicted, i);
      for (const int j : g[i]) g_pi[perm[i]].push_back(perm[j]);
      z_pi[perm[i]] = z[i];
      p_pi[perm[i]] = p[i];
    }

    Eigen::MatrixXd W, W_pi;
    FusionWeights(g, 0.75, &W);
    FusionWeights(g_pi, 0.75, &W_pi);
    BeliefSet fused, fused_pi;
    Fuse(predicted, W, z, p, &fused);
    Fuse(predicted_pi, W_pi, z_pi, p_pi, &fused_pi);

    BeliefSet unpermuted(&layout, n);
    for (int i = 0; i < n; ++i) unpermuted.CopyRow(i, fused_pi, perm[i]);
    EXPECT_LT(MaxRelDiff(unpermuted.data(), fused.data()), 1e-12)
        << "density " << density;
  }
}

// Repeated fusion without measurements: every robot converges to one belief.
// Returns the largest deviation from robot 0 relative to the largest entry.
double Disagreement(const BeliefSet& beliefs) {
  const BeliefSet::Storage b = beliefs.Materialized();
  double worst = 0.0;
  for (int i = 1; i < b.rows(); ++i)
    worst = std::max(worst, (b.row(i) - b.row(0)).cwiseAbs().maxCoeff());
  return worst / b.cwiseAbs().maxCoeff();
}

void FuseRepeatedly(const Graph& g, int steps, BeliefSet* beliefs) {
  const int n = beliefs->rows();
  Eigen::MatrixXd W;
  FusionWeights(g, 0.75, &W);
  const Measurements none(n);
  const std::vector<Vec2> p(n, Vec2::Zero());
  BeliefSet next(&beliefs->layout(), n);
  for (int t = 0; t < steps; ++t) {
    Fuse(*beliefs, W, none, p, &next);
    std::swap(*beliefs, next);
  }
}

TEST(ConsensusTest, RingAgreesAndKeepsTheAverage) {
  Rng rng(17);
  const BeliefLayout layout({StaticModel(2), StaticModel(4)});
  const int n = 8;
  Graph ring(n);
  for (int i = 0; i < n; ++i) ring[i] = {(i + n - 1) % n, (i + 1) % n};
  BeliefSet beliefs(&layout, n);
  Randomize(&beliefs, &rng);
  const Eigen::RowVectorXd average = beliefs.data().colwise().mean();
  ASSERT_GT(Disagreement(beliefs), 0.1);
  // Second eigenvalue of W: 0.75 + 0.25 cos(2 pi / 8) = 0.927; 0.927^400 ~
  // 1e-13.
  FuseRepeatedly(ring, 400, &beliefs);
  EXPECT_LT(Disagreement(beliefs), 1e-8);
  // Every node has two neighbours, so W is symmetric, hence doubly stochastic.
  const Eigen::RowVectorXd after = beliefs.data().colwise().mean();
  EXPECT_LT(
      (after - average).cwiseAbs().maxCoeff() / average.cwiseAbs().maxCoeff(),
      1e-12);
  EXPECT_TRUE(AllBlocksSpd(beliefs));
}

TEST(ConsensusTest, FullGraphAgreesAndKeepsTheAverage) {
  Rng rng(19);
  const BeliefLayout layout({StaticModel(2), StaticModel(4)});
  const int n = 30;
  BeliefSet beliefs(&layout, n);
  Randomize(&beliefs, &rng);
  const Eigen::RowVectorXd average = beliefs.data().colwise().mean();
  FuseRepeatedly(FullGraph(n), 100, &beliefs);
  EXPECT_LT(Disagreement(beliefs), 1e-8);
  const Eigen::RowVectorXd after = beliefs.data().colwise().mean();
  EXPECT_LT(
      (after - average).cwiseAbs().maxCoeff() / average.cwiseAbs().maxCoeff(),
      1e-12);
}

TEST(ConsensusTest, RandomConnectedGraphAgrees) {
  Rng rng(23);
  const BeliefLayout layout({StaticModel(2), StaticModel(4)});
  const int n = 15;
  // A path through all robots keeps the graph connected; extra random edges
  // make the degrees (and so the rows of W) differ.
  Graph g(n);
  for (int i = 0; i + 1 < n; ++i) {
    g[i].push_back(i + 1);
    g[i + 1].push_back(i);
  }
  for (int i = 0; i < n; ++i) {
    for (int j = i + 2; j < n; ++j) {
      if (rng.Bernoulli(0.2)) {
        g[i].push_back(j);
        g[j].push_back(i);
      }
    }
  }
  BeliefSet beliefs(&layout, n);
  Randomize(&beliefs, &rng);
  FuseRepeatedly(g, 1500, &beliefs);
  EXPECT_LT(Disagreement(beliefs), 1e-8);
  EXPECT_TRUE(AllBlocksSpd(beliefs));
}

// ---------------------------------------------------------------------------
// Long runs and the centralized filter.

TEST(FilterTest, CovariancesStaySpdOverManySteps) {
  Rng rng(29);
  TargetModel drift = StaticModel(2);
  drift.A << 0.999, 0.02, -0.02, 0.999;
  drift.b << 0.05, 0.0;
  drift.q = 1e-3;
  const std::vector<TargetModel> models = {
      ConstantVelocity(0.01), StaticModel(2), drift, ConstantVelocity(1e-4),
      StaticModel(2)};
  const BeliefLayout layout(models);
  const int n = 10;
  const int m = layout.num_targets();
  std::vector<Eigen::VectorXd> truth, means;
  std::vector<Eigen::MatrixXd> covs;
  for (int k = 0; k < m; ++k) {
    const int d = layout.dim(k);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(d);
    x.head<2>() = Vec2(rng.Uniform(2.0, 8.0), rng.Uniform(2.0, 8.0));
    if (d == 4) x.tail<2>() = Vec2(0.05 * rng.Normal(), 0.05 * rng.Normal());
    truth.push_back(x);
    means.push_back(Eigen::VectorXd::Constant(d, 5.0));
    covs.push_back(4.0 * Eigen::MatrixXd::Identity(d, d));
  }
  BeliefSet beliefs(&layout, n);
  BeliefSet fused(&layout, n);
  BeliefSet central(&layout, 1);
  beliefs.SetPrior(means, covs);
  central.SetPrior(means, covs);
  std::vector<Vec2> p = RandomPositions(n, &rng);
  const SensorModel sensor;
  Eigen::MatrixXd W;
  int num_measurements = 0;

  for (int t = 0; t < 300; ++t) {
    for (int k = 0; k < m; ++k) {
      const TargetModel& tm = layout.model(k);
      truth[k] = tm.A * truth[k] + tm.b;
      for (int d = 0; d < tm.dim(); ++d)
        truth[k](d) += std::sqrt(tm.q) * rng.Normal();
    }
    Measurements z(n);
    for (int i = 0; i < n; ++i) {
      p[i] += Vec2(0.3 * rng.Normal(), 0.3 * rng.Normal());
      for (int k = 0; k < m; ++k) {
        const Vec2 rel = truth[k].head<2>() - p[i];
        if (!sensor.InRange(rel.norm())) continue;
        const double s = sensor.Std(rel.norm());
        const Vec2 y = rel + s * Vec2(rng.Normal(), rng.Normal());
        z[i].push_back({k, y, sensor.Precision(y.norm())});
        ++num_measurements;
      }
    }
    Predict(&beliefs);
    Predict(&central);
    FusionWeights(RandomGraph(n, 0.4, &rng), 0.75, &W);
    Fuse(beliefs, W, z, p, &fused);
    std::swap(beliefs, fused);
    CentralUpdate(z, p, &central);
    ASSERT_TRUE(AllBlocksSpd(beliefs)) << "step " << t;
    ASSERT_TRUE(AllBlocksSpd(central)) << "step " << t;
    // Omega_i <= Omega_central in the Loewner order (prediction is monotone
    // and sum_j kappa_ij Omega_j + Z_i <= Omega^- + sum_i Z_i), so no robot
    // is ever more certain than the centralized filter.
    for (int i = 0; i < n; ++i) {
      for (int k = 0; k < m; ++k) {
        EXPECT_LE(central.LogDetCovariance(0, k),
                  beliefs.LogDetCovariance(i, k) + 1e-9)
            << "step " << t << " robot " << i << " target " << k;
      }
    }
  }
  EXPECT_GT(num_measurements, 300);  // the run did exercise the update
}

TEST(CentralUpdateTest, SumsEveryRobotsMeasurementsByHand) {
  const BeliefLayout layout({StaticModel(2), StaticModel(2)});
  BeliefSet central(&layout, 1);
  central.SetPrior({Eigen::Vector2d::Zero(), Eigen::Vector2d(1.0, 1.0)},
                   {Eigen::Matrix2d::Identity(), Eigen::Matrix2d::Identity()});
  // Both robots see target 0 at absolute position y + p = (2, 3):
  //   Omega = I + 4 I + 1 I = 6 I,  xi = 4 (2, 3) + 1 (2, 3) = (10, 15),
  //   mu = (10, 15) / 6.  Target 1 is seen by nobody and keeps its prior.
  CentralUpdate({{{0, Vec2(1.0, 2.0), 4.0}}, {{0, Vec2(-1.0, 0.0), 1.0}}},
                {Vec2(1.0, 1.0), Vec2(3.0, 3.0)}, &central);
  EXPECT_TRUE(
      central.Omega(0, 0).isApprox(6.0 * Eigen::Matrix2d::Identity(), 1e-15));
  EXPECT_TRUE(central.Xi(0, 0).isApprox(Eigen::Vector2d(10.0, 15.0), 1e-15));
  EXPECT_TRUE(
      central.PositionMean(0, 0).isApprox(Vec2(10.0 / 6.0, 2.5), 1e-14));
  EXPECT_TRUE(central.Omega(0, 1).isApprox(Eigen::Matrix2d::Identity(), 1e-15));
  EXPECT_TRUE(central.Xi(0, 1).isApprox(Eigen::Vector2d(1.0, 1.0), 1e-15));
}

TEST(AllBlocksSpdTest, RejectsAsymmetricIndefiniteAndNonFiniteBlocks) {
  const BeliefLayout layout({StaticModel(2), StaticModel(4)});
  BeliefSet beliefs(&layout, 2);
  beliefs.SetPrior({Eigen::Vector2d::Zero(), Eigen::Vector4d::Zero()},
                   {Eigen::Matrix2d::Identity(), Eigen::Matrix4d::Identity()});
  ASSERT_TRUE(AllBlocksSpd(beliefs));

  BeliefSet bad = beliefs;
  bad.Omega(1, 1)(0, 3) = 1e-3;  // asymmetric
  EXPECT_FALSE(AllBlocksSpd(bad));
  EXPECT_TRUE(AllBlocksSpd(bad, 1e-2));

  bad = beliefs;
  bad.Omega(1, 0)(1, 1) = -1.0;  // indefinite
  EXPECT_FALSE(AllBlocksSpd(bad));

  bad = beliefs;
  bad.Omega(0, 1)(2, 2) = std::nan("");
  EXPECT_FALSE(AllBlocksSpd(bad));
}

TEST(FuseTest, SizesTheOutputOnceThenReusesIt) {
  Rng rng(31);
  const BeliefLayout layout({StaticModel(2)});
  BeliefSet predicted(&layout, 5);
  Randomize(&predicted, &rng);
  Eigen::MatrixXd W;
  FusionWeights(FullGraph(5), 0.75, &W);
  const Measurements none(5);
  const std::vector<Vec2> p(5, Vec2::Zero());
  BeliefSet out;
  Fuse(predicted, W, none, p, &out);
  ASSERT_EQ(out.rows(), 5);
  const double* storage = out.data().data();
  Fuse(predicted, W, none, p, &out);
  EXPECT_EQ(out.data().data(), storage);
}

// The planners' covariance-only time update is the filter's own: the same
// Omega, exactly, as the full block update.
TEST(FilterTest, PredictInformationMatrixIsTheBlockUpdatesOmega) {
  Rng rng(41);
  TargetModel drift = StaticModel(2);
  drift.A << 0.9, 0.3, -0.2, 1.1;
  drift.q = 0.02;
  for (const TargetModel& model : {drift, ConstantVelocity(0.05)}) {
    const int d = model.dim();
    const Eigen::MatrixXd omega = RandomSpd(d, &rng);
    std::vector<double> block(d * d + d, 0.0), matrix(d * d);
    std::copy(omega.data(), omega.data() + d * d, block.begin());
    std::copy(omega.data(), omega.data() + d * d, matrix.begin());
    for (int i = 0; i < d; ++i) block[d * d + i] = rng.Normal();
    PredictInformationBlock(model, block.data());
    PredictInformationMatrix(model, matrix.data());
    for (int i = 0; i < d * d; ++i) EXPECT_EQ(matrix[i], block[i]) << i;
  }
}

// Numerical stress (issue 11): 100 000 DKF steps under extreme settings
// within the scenario ranges. Every block stays finite, symmetric and
// positive definite, and log det Sigma stays finite, whatever the scale.
struct StressCase {
  const char* name;
  TargetModel model;
  double prior_sigma;
  double precision;   // per measurement; 0: never seen
  double seen_share;  // share of steps with a measurement
};

TargetModel Scaled(int dim, double a, double q) {
  TargetModel m = StaticModel(dim);
  m.A *= a;
  m.q = q;
  return m;
}

TEST(FilterStressTest, HundredThousandStepsKeepEveryBlockSpd) {
  TargetModel fast = ConstantVelocity(1e6);  // huge noise, fast dynamics
  fast.A(0, 2) = fast.A(1, 3) = 1e3;
  // Unstable but observable: the velocity shows in the position.
  TargetModel unstable = ConstantVelocity(1e-3);
  unstable.A *= 1.05;
  TargetModel rotating = StaticModel(2);
  rotating.A << 0.0, -1.0, 1.0, 0.0;
  const std::vector<StressCase> cases = {
      {"tiny noise, huge prior, precise sensor", ConstantVelocity(1e-12), 1e6,
       1e12, 1.0},
      {"huge noise, tiny prior, poor sensor", ConstantVelocity(1e6), 1e-6, 1e-8,
       0.5},
      {"never seen, slow random walk", Scaled(4, 1.0, 1e-6), 1e6, 0.0, 0.0},
      {"fast dynamics, huge noise, seen", fast, 1.0, 1e12, 1.0},
      {"contracting, no noise", Scaled(2, 0.5, 0.0), 1.0, 1e12, 0.3},
      {"rotating, no noise, precise", rotating, 1e-6, 1e12, 1.0},
      {"slightly unstable, watched", unstable, 1e3, 1e4, 1.0},
  };
  constexpr int kSteps = 100000;
  constexpr int kRobots = 3;
  for (const StressCase& c : cases) {
    SCOPED_TRACE(c.name);
    const BeliefLayout layout({c.model});
    const int d = c.model.dim();
    BeliefSet beliefs(&layout, kRobots), predicted(&layout, kRobots);
    beliefs.SetPrior(
        {Eigen::VectorXd::Zero(d)},
        {c.prior_sigma * c.prior_sigma * Eigen::MatrixXd::Identity(d, d)});
    Rng rng(7);
    Eigen::MatrixXd W;
    std::vector<Vec2> positions(kRobots, Vec2(1.0, 2.0));
    Measurements z(kRobots);
    int checked = 0;
    for (int t = 0; t < kSteps; ++t) {
      predicted.data() = beliefs.data();
      ASSERT_NO_THROW(Predict(&predicted)) << "step " << t;
      FusionWeights(RandomGraph(kRobots, 0.5, &rng), 0.75, &W);
      for (int i = 0; i < kRobots; ++i) {
        z[i].clear();
        if (c.precision > 0.0 && rng.Bernoulli(c.seen_share))
          z[i].push_back({0, Vec2(rng.Normal(), rng.Normal()), c.precision});
      }
      Fuse(predicted, W, z, positions, &beliefs);
      if (t % 1000 == 999 || t == 0) {
        ++checked;
        ASSERT_TRUE(beliefs.data().allFinite()) << "step " << t;
        ASSERT_TRUE(AllBlocksSpd(beliefs, 1e-9)) << "step " << t;
        for (int i = 0; i < kRobots; ++i) {
          ASSERT_TRUE(std::isfinite(beliefs.LogDetCovariance(i, 0)))
              << "step " << t;
          ASSERT_TRUE(beliefs.Mean(i, 0).allFinite()) << "step " << t;
        }
      }
    }
    EXPECT_EQ(checked, kSteps / 1000 + 1);
  }
}

// Where the model itself diverges (unstable A, no measurements), the filter
// says so with EstimateDiverged instead of aborting or going on with inf.
// Nine robots in a clique, each missing only the tenth, which is cut off
// and measures an unstable target every step: the clique's information of
// it decays toward the bound while the tenth's grows. The sum trick's
// S - B_i - B_9 then cancels to rounding error of the tenth's size (an
// Omega stuck near 1e-14, or exactly 0 and a "not positive definite"
// abort); the blocks are summed directly there, and every row matches the
// DKF's direct sum over its neighbours (within 1e-5: the sum trick's error
// where it is kept is at most about 1e-6 of the result).
TEST(FuseTest, RowsCutOffFromTheOneThatMeasuresKeepTheirOwnNumbers) {
  const TargetModel unstable = Scaled(2, 1.1, 1e-6);
  const BeliefLayout layout({unstable});
  const int n = 10;
  const double kappa = 0.302;
  Graph g(n);
  for (int i = 0; i < n - 1; ++i)
    for (int j = 0; j < n - 1; ++j)
      if (j != i) g[i].push_back(j);
  DkfWeights w;
  MakeDkfWeights(g, kappa, &w);
  BeliefSet fused(&layout, n), predicted(&layout, n), direct(&layout, n);
  fused.SetPrior({Eigen::Vector2d(1.0, 2.0)}, {Eigen::Matrix2d::Identity()});
  direct = fused;
  Measurements z(n);
  z[n - 1].push_back(Measurement{0, Vec2(1.0, 2.0), 63.74});
  const std::vector<Vec2> p(n, Vec2::Zero());
  for (int t = 0; t < 300; ++t) {
    predicted = fused;
    ASSERT_NO_THROW(Predict(&predicted)) << "step " << t;
    Fuse(predicted, w, z, p, &fused);
    // The reference: predict each row, then kappa B_i + off sum_{j in N_i}
    // B_j term by term.
    for (int i = 0; i < n; ++i)
      PredictInformationBlock(unstable, direct.data().row(i).data());
    const BeliefSet::Storage before = direct.data();
    for (int i = 0; i < n; ++i) {
      Eigen::RowVectorXd row = w.self[i] * before.row(i);
      for (const int j : g[i]) row += w.off[i] * before.row(j);
      direct.data().row(i) = row;
    }
    AddMeasurements(z[n - 1], p[n - 1], &direct, n - 1);
    for (int i = 0; i < n; ++i)
      for (int e = 0; e < direct.data().cols(); ++e)
        ASSERT_NEAR(fused.data()(i, e), direct.data()(i, e),
                    1e-5 * std::abs(direct.data()(i, e)))
            << "step " << t << " row " << i << " entry " << e;
  }
  EXPECT_TRUE(AllBlocksSpd(fused));
  // The clique's variance reached the bound; the tenth's stays small.
  EXPECT_NEAR(fused.Omega(0, 0)(0, 0), 1.0 / kMaxVariance, 1e-6 / kMaxVariance);
  EXPECT_GT(fused.Omega(n - 1, 0)(0, 0), 100.0);
}

// Failed robots keep their rows but are nobody's neighbour: those rows stay
// out of the column sum, not subtracted again from every other row (F x N x
// M work a step, and a subtraction that cancels where the failed rows hold
// most of the information: here 1e6 times the others', which left the
// active rows an error of about 1e-11 of their values).
TEST(FuseTest, RowsThatAreNobodysNeighbourStayOutOfTheColumnSum) {
  Rng rng(12);
  const BeliefLayout layout({StaticModel(2), ConstantVelocity(0.1)});
  const int n = 40, failed = 10;
  Graph g(n);
  for (int i = 0; i < n - failed; ++i)
    for (int j = 0; j < n - failed; ++j)
      if (j != i) g[i].push_back(j);
  DkfWeights w;
  MakeDkfWeights(g, 0.6, &w);
  BeliefSet predicted(&layout, n), fused(&layout, n);
  Randomize(&predicted, &rng);
  for (int i = n - failed; i < n; ++i) predicted.data().row(i) *= 1e6;
  const Measurements z = RandomMeasurements(n, layout.num_targets(), &rng);
  const std::vector<Vec2> p = RandomPositions(n, &rng);
  Fuse(predicted, w, z, p, &fused);
  BeliefSet direct(&layout, n);
  for (int i = 0; i < n; ++i) {
    Eigen::RowVectorXd row = w.self[i] * predicted.data().row(i);
    for (const int j : g[i]) row += w.off[i] * predicted.data().row(j);
    direct.data().row(i) = row;
    AddMeasurements(z[i], p[i], &direct, i);
  }
  for (int i = 0; i < n; ++i) {
    const double scale = direct.data().row(i).cwiseAbs().maxCoeff();
    EXPECT_LT(
        (fused.data().row(i) - direct.data().row(i)).cwiseAbs().maxCoeff(),
        1e-14 * scale)
        << "row " << i;
  }
}

TEST(FilterStressTest, DivergingDynamicsThrowEstimateDiverged) {
  const BeliefLayout layout({StaticModel(2), Scaled(2, 2.0, 0.01)});
  BeliefSet beliefs(&layout, 2);
  beliefs.SetPrior({Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()},
                   {Eigen::Matrix2d::Identity(), Eigen::Matrix2d::Identity()});
  int step = 0;
  try {
    for (; step < 1000; ++step) Predict(&beliefs);
    FAIL() << "no divergence reported";
  } catch (const EstimateDiverged& e) {
    EXPECT_EQ(e.target(), 1);
    EXPECT_NE(std::string(e.what()).find("variance"), std::string::npos);
  }
  // 4^t grows past 1e24 at t = 40.
  EXPECT_EQ(step, 39);
  // Planners looking ahead saturate at kMaxVariance instead.
  Eigen::Matrix2d omega = Eigen::Matrix2d::Identity();
  for (int t = 0; t < 1000; ++t)
    PredictInformationMatrix(Scaled(2, 2.0, 0.01), omega.data());
  EXPECT_TRUE(omega.allFinite());
  EXPECT_NEAR(1.0 / omega(0, 0), kMaxVariance, 1e-6 * kMaxVariance);
}

// A failed robot's belief of an unstable target (x' = 2x, nothing measured)
// doubled its mean every step until it overflowed, some 1030 steps in, and
// that ended the mission while a teammate measured the target every step.
// Its mean is held at kMaxMean now, as its variance at kMaxVariance, and
// only a target that no counted row keeps within the bounds diverges.
TEST(FilterStressTest, AnUnmeasuredRowOfAnUnstableTargetStaysWithinTheBounds) {
  const BeliefLayout layout({Scaled(2, 2.0, 0.0)});
  BeliefSet b(&layout, 2);
  b.SetPrior({Eigen::Vector2d(5.0, 6.0)}, {Eigen::Matrix2d::Identity()});
  const std::vector<std::uint8_t> active{1, 0};  // row 1 failed
  for (int t = 0; t < 1500; ++t) {
    ASSERT_NO_THROW(Predict(&b, &active)) << "step " << t;
    AddMeasurements({Measurement{0, Vec2(5.0, 6.0), 100.0}}, Vec2::Zero(), &b,
                    0);
  }
  const Eigen::VectorXd lost = b.Mean(1, 0);
  ASSERT_TRUE(lost.allFinite());
  EXPECT_EQ(lost.cwiseAbs().maxCoeff(), kMaxMean);
  EXPECT_GT(b.Omega(0, 0)(0, 0), 10.0);  // the measured row is sure of it
  // With the lost row alone counted, the target diverges, saying why.
  const std::vector<std::uint8_t> only_lost{0, 1};
  try {
    Predict(&b, &only_lost);
    FAIL() << "no divergence reported";
  } catch (const EstimateDiverged& e) {
    EXPECT_EQ(e.target(), 0);
    EXPECT_NE(std::string(e.what()).find("in every estimate that counts"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace aia

namespace aia {
namespace {

// The shared fusion (a full graph's: target by target, common blocks
// summed in runs) against the row-by-row fusion, to the bit, over a
// mission's worth of steps: the same robots beside one more row that
// nobody hears and that mixes with weights of its own (so the whole step
// goes row by row, and leaves the others' numbers alone). Rows measure now
// and then, some messages are lost, a robot fails, and some targets move.
TEST(FuseTest, SharedFusionIsTheRowByRowFusionToTheBit) {
  Rng rng(20261208);
  std::vector<TargetModel> models;
  for (int k = 0; k < 24; ++k)
    models.push_back(k % 4 == 1 ? ConstantVelocity(0.01) : StaticModel(2));
  const BeliefLayout layout(models);
  const int n = 64, m = layout.num_targets();
  std::vector<Eigen::VectorXd> means;
  std::vector<Eigen::MatrixXd> covs;
  for (int k = 0; k < m; ++k) {
    const int d = layout.dim(k);
    means.push_back(Eigen::VectorXd::Random(d) * 5.0);
    covs.push_back(RandomSpd(d, &rng));
  }
  BeliefSet shared(&layout, n), next(&layout, n);
  shared.SetPrior(means, covs);
  ASSERT_TRUE(shared.sharing());
  BeliefSet rows(&layout, n + 1), rows_next(&layout, n + 1);
  rows.SetPrior(means, covs);
  rows.Unshare();
  ThreadPool pool(2);
  const RangeRunner threads = PoolRunner(&pool);
  int steps_shared = 0;
  // Whether row i measured target k, or missed a message, so far.
  std::vector<char> touched(static_cast<std::size_t>(n) * m, 0);
  const auto touch_all = [&](int i) {
    std::fill_n(touched.begin() + static_cast<std::ptrdiff_t>(i) * m, m, 1);
  };
  for (int t = 0; t < 60; ++t) {
    Graph g = FullGraph(n);
    if (t == 40) {  // nine robots miss a message: too many for the shared mix
      for (int i = 20; i < 29; ++i) {
        g[i].erase(std::find(g[i].begin(), g[i].end(), i + 1));
        touch_all(i);
      }
    }
    if (t % 7 == 3) {  // lost messages: robot 5 misses 9's, 12 misses 0's
      g[5].erase(std::find(g[5].begin(), g[5].end(), 9));
      g[12].erase(g[12].begin());
      touch_all(5);
      touch_all(12);
    }
    if (t >= 30) {  // robot 17 failed: nobody hears it, it hears nobody
      g[17].clear();
      for (int i = 0; i < n; ++i)
        if (i != 17) g[i].erase(std::find(g[i].begin(), g[i].end(), 17));
      touch_all(17);
    }
    Measurements z(n);
    for (int i = 0; i < n; ++i)
      if (rng.Bernoulli(0.02)) {
        const int k = static_cast<int>(rng.Uniform(0.0, m - 0.5));
        z[i].push_back(
            {k, Vec2(rng.Normal(), rng.Normal()), rng.Uniform(1.0, 400.0)});
        touched[static_cast<std::size_t>(i) * m + k] = 1;
      }
    const std::vector<Vec2> p = RandomPositions(n, &rng);
    Predict(&shared, nullptr, t % 2 ? threads : RangeRunner{});
    Predict(&rows);
    DkfWeights w;
    MakeDkfWeights(g, 0.75, &w);
    Fuse(shared, w, z, p, &next, t % 2 ? threads : RangeRunner{});
    steps_shared += next.sharing();
    EXPECT_EQ(next.sharing(), t != 40) << "step " << t;
    // The extra row: 0.5 itself, 0.3 and 0.2 from robots 0 and 1.
    Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n + 1, n + 1);
    FusionWeights(g, 0.75, &W);
    Eigen::MatrixXd Wx = Eigen::MatrixXd::Zero(n + 1, n + 1);
    Wx.topLeftCorner(n, n) = W.topLeftCorner(n, n);
    Wx(n, n) = 0.5;
    Wx(n, 0) = 0.3;
    Wx(n, 1) = 0.2;
    Measurements zx = z;
    zx.emplace_back();
    std::vector<Vec2> px = p;
    px.emplace_back(0.0, 0.0);
    Fuse(rows, Wx, zx, px, &rows_next);
    ASSERT_FALSE(rows_next.sharing());
    std::swap(shared, next);
    std::swap(rows, rows_next);
    const BeliefSet::Storage a = shared.Materialized();
    ASSERT_TRUE(a == rows.data().topRows(n)) << "step " << t;
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < m; ++k)
        ASSERT_EQ(shared.DetCovariance(i, k), rows.DetCovariance(i, k));
  }
  // Every step shared but the one with too many special rows (row by
  // row), after which the set shares again; a robot that heard every
  // message and never measured a target holds its common block.
  EXPECT_EQ(steps_shared, 59);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < m; ++k)
      if (!touched[static_cast<std::size_t>(i) * m + k])
        EXPECT_TRUE(shared.Shared(i, k)) << i << " " << k;
  EXPECT_FALSE(shared.Shared(17, 0));  // failed: predicted alone
}

}  // namespace
}  // namespace aia
