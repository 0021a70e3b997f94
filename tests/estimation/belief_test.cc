#include "aia/estimation/belief.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <vector>

#include "aia/core/rng.h"

namespace aia {
namespace {

TargetModel Model(int dim) { return TargetModel::Static(dim); }

Eigen::MatrixXd RandomSpd(int dim, Rng* rng) {
  Eigen::MatrixXd a(dim, dim);
  for (int i = 0; i < a.size(); ++i) a.data()[i] = rng->Normal();
  return a * a.transpose() + 0.5 * Eigen::MatrixXd::Identity(dim, dim);
}

Eigen::VectorXd RandomVector(int dim, Rng* rng) {
  Eigen::VectorXd v(dim);
  for (int i = 0; i < dim; ++i) v(i) = rng->Normal();
  return v;
}

TEST(BeliefLayoutTest, BlocksArePackedOmegaThenXi) {
  TargetModel moving = Model(4);
  moving.A(0, 2) = 1.0;
  const BeliefLayout layout({Model(2), moving, Model(2)});
  ASSERT_EQ(layout.num_targets(), 3);
  EXPECT_TRUE(layout.is_static(0));
  EXPECT_FALSE(layout.is_static(1));
  EXPECT_FALSE(layout.all_static());
  // 2x2 + 2 = 6, 4x4 + 4 = 20, 6.
  EXPECT_EQ(layout.omega_offset(0), 0);
  EXPECT_EQ(layout.xi_offset(0), 4);
  EXPECT_EQ(layout.omega_offset(1), 6);
  EXPECT_EQ(layout.xi_offset(1), 22);
  EXPECT_EQ(layout.omega_offset(2), 26);
  EXPECT_EQ(layout.xi_offset(2), 30);
  EXPECT_EQ(layout.stride(), 32);
  EXPECT_FALSE(layout.all_static());
  EXPECT_TRUE(BeliefLayout({Model(2), Model(4)}).all_static());
}

TEST(BeliefSetTest, SetPriorRoundTripsMeanAndCovariance) {
  Rng rng(11);
  const BeliefLayout layout({Model(2), Model(4), Model(2)});
  std::vector<Eigen::VectorXd> means;
  std::vector<Eigen::MatrixXd> covs;
  for (int k = 0; k < layout.num_targets(); ++k) {
    means.push_back(RandomVector(layout.dim(k), &rng));
    covs.push_back(RandomSpd(layout.dim(k), &rng));
  }
  BeliefSet beliefs(&layout, 3);
  beliefs.SetPrior(means, covs);
  for (int r = 0; r < beliefs.rows(); ++r) {
    EXPECT_EQ(beliefs.data().row(r), beliefs.data().row(0));
    for (int k = 0; k < layout.num_targets(); ++k) {
      EXPECT_TRUE(beliefs.Mean(r, k).isApprox(means[k], 1e-12))
          << r << " " << k;
      EXPECT_TRUE(beliefs.Covariance(r, k).isApprox(covs[k], 1e-12))
          << r << " " << k;
      const Eigen::MatrixXd omega = beliefs.Omega(r, k);
      EXPECT_EQ(omega, omega.transpose());  // exactly, not approximately
      EXPECT_TRUE(
          (omega * covs[k])
              .isApprox(Eigen::MatrixXd::Identity(layout.dim(k), layout.dim(k)),
                        1e-12));
    }
  }
}

TEST(BeliefSetTest, PositionMarginalsAreTheFirstTwoCoordinates) {
  Rng rng(12);
  const BeliefLayout layout({Model(4), Model(2)});
  BeliefSet beliefs(&layout, 1);
  beliefs.SetPrior({RandomVector(4, &rng), RandomVector(2, &rng)},
                   {RandomSpd(4, &rng), RandomSpd(2, &rng)});
  for (int k = 0; k < 2; ++k) {
    EXPECT_TRUE(beliefs.PositionMean(0, k).isApprox(
        beliefs.Mean(0, k).head<2>(), 1e-14));
    const Eigen::MatrixXd sigma = beliefs.Covariance(0, k);
    EXPECT_TRUE(beliefs.PositionCovariance(0, k).isApprox(
        sigma.topLeftCorner(2, 2), 1e-14));
  }
}

TEST(BeliefSetTest, DetAndLogDetAgree) {
  Rng rng(13);
  const BeliefLayout layout({Model(2), Model(4)});
  BeliefSet beliefs(&layout, 1);
  for (int trial = 0; trial < 20; ++trial) {
    beliefs.SetPrior({RandomVector(2, &rng), RandomVector(4, &rng)},
                     {RandomSpd(2, &rng), RandomSpd(4, &rng)});
    for (int k = 0; k < 2; ++k) {
      const double det = beliefs.Covariance(0, k).determinant();
      EXPECT_NEAR(beliefs.DetCovariance(0, k), det, 1e-12 * det);
      EXPECT_NEAR(beliefs.LogDetCovariance(0, k), std::log(det), 1e-12);
    }
  }
}

TEST(BeliefSetTest, LogDetStaysFiniteWhereDetOverflows) {
  const BeliefLayout layout({Model(4)});
  BeliefSet beliefs(&layout, 1);
  // det Omega = 1e360 overflows a double; log det Sigma = -4 log 1e90 does not.
  beliefs.Omega(0, 0) = 1e90 * Eigen::Matrix4d::Identity();
  EXPECT_EQ(beliefs.DetCovariance(0, 0), 0.0);
  EXPECT_NEAR(beliefs.LogDetCovariance(0, 0), -4.0 * 90.0 * std::log(10.0),
              1e-10);
}

// A position known to 1e-4 m beside a loosely known velocity, correlated
// (a constant-velocity target after a few measurements): Omega = L L' with
// det L = 1e4, so det Sigma = 1e-8. The 4 x 4 cofactor formula cancels here (it
// gave 14.87 for 16.00 on such a block in a run); the Cholesky factor's
// diagonal does not.
TEST(BeliefSetTest, DetOfABadlyScaledFourDimensionalBlock) {
  const BeliefLayout layout({Model(4)});
  BeliefSet beliefs(&layout, 1);
  Eigen::Matrix4d l = Eigen::Matrix4d::Zero();
  l.diagonal() << 1e4, 1e4, 1e-2, 1e-2;
  l(2, 0) = l(3, 1) = 1e3;
  l(3, 0) = 37.0;
  const Eigen::Matrix4d omega = l * l.transpose();
  beliefs.Omega(0, 0) = omega;
  const double det = beliefs.DetCovariance(0, 0);
  EXPECT_NEAR(det, std::exp(beliefs.LogDetCovariance(0, 0)), 1e-9 * det);
  EXPECT_NEAR(det, 1e-8, 1e-11);
  // What the cofactor formula makes of the same block.
  EXPECT_GT(std::abs(1.0 / omega.determinant() / 1e-8 - 1.0), 1e-3)
      << 1.0 / omega.determinant();
}

TEST(BeliefSetTest, NoInformationMeansUnboundedCovariance) {
  const BeliefLayout layout({Model(2)});
  const BeliefSet beliefs(&layout, 1);  // Omega = 0
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(beliefs.DetCovariance(0, 0), inf);
  EXPECT_EQ(beliefs.LogDetCovariance(0, 0), inf);
}

// A block that is not positive definite holds no estimate, in either
// dimension, though its det Omega may be positive (-I: 1).
TEST(BeliefSetTest, IndefiniteOrNegativeBlocksHaveUnboundedCovariance) {
  const double inf = std::numeric_limits<double>::infinity();
  for (const int d : {2, 4}) {
    const BeliefLayout layout({Model(d)});
    BeliefSet beliefs(&layout, 2);
    beliefs.Omega(0, 0) = -Eigen::MatrixXd::Identity(d, d);
    beliefs.Omega(1, 0) = Eigen::MatrixXd::Identity(d, d);
    beliefs.Omega(1, 0)(0, 0) = -1.0;
    beliefs.Omega(1, 0)(1, 1) = -1.0;  // det > 0, indefinite for d = 4
    for (int r = 0; r < 2; ++r) {
      EXPECT_EQ(beliefs.DetCovariance(r, 0), inf) << "d " << d << " row " << r;
      EXPECT_EQ(beliefs.LogDetCovariance(r, 0), inf)
          << "d " << d << " row " << r;
    }
  }
}

TEST(BeliefSetTest, CopyRowCopiesEveryBlock) {
  Rng rng(14);
  const BeliefLayout layout({Model(2), Model(4)});
  BeliefSet from(&layout, 3);
  for (int i = 0; i < from.data().size(); ++i)
    from.data().data()[i] = rng.Normal();
  BeliefSet to(&layout, 2);
  to.CopyRow(1, from, 2);
  EXPECT_EQ(to.data().row(1), from.data().row(2));
  EXPECT_TRUE(to.data().row(0).isZero(0.0));
}

// The digest holds exactly what the belief set answers, for every row and
// target, 2-D and 4-D blocks alike, however its rows are split.
TEST(BeliefDigestTest, HoldsTheLogDetsAndMeansOfEveryBlock) {
  Rng rng(15);
  const BeliefLayout layout({Model(2), Model(4), Model(2)});
  BeliefSet beliefs(&layout, 5);
  std::vector<Eigen::VectorXd> means;
  std::vector<Eigen::MatrixXd> covs;
  for (int k = 0; k < 3; ++k) {
    means.push_back(RandomVector(layout.dim(k), &rng));
    covs.push_back(RandomSpd(layout.dim(k), &rng));
  }
  beliefs.SetPrior(means, covs);
  for (int r = 1; r < 5; ++r)
    for (int k = 0; k < 3; ++k) {
      beliefs.Omega(r, k) = RandomSpd(layout.dim(k), &rng);
      beliefs.Xi(r, k) = RandomVector(layout.dim(k), &rng);
    }
  // A block without a Cholesky factor (the filter's fallback path).
  beliefs.Omega(4, 0) << 1.0, 0.0, 0.0, -2.0;
  BeliefDigest serial, split;
  serial.Compute(beliefs);
  EXPECT_TRUE(std::isinf(serial.LogDet(4, 0)));
  EXPECT_TRUE(serial.Mean(4, 0).allFinite());
  split.Compute(beliefs, [](int n, const RangeTask& f) {
    f(0, 2, 0);
    f(2, n, 1);
  });
  for (int r = 0; r < 5; ++r)
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(serial.LogDet(r, k), beliefs.LogDetCovariance(r, k));
      EXPECT_EQ(serial.Mean(r, k), beliefs.PositionMean(r, k));
      EXPECT_EQ(split.LogDet(r, k), serial.LogDet(r, k));
      EXPECT_EQ(split.Mean(r, k), serial.Mean(r, k));
    }
}

// Runs of rows that hold one belief of a target (a full graph's usual
// state), across the split too: each row's values are still exactly what
// the belief set answers for it.
TEST(BeliefDigestTest, RowsHoldingTheRowBeforesBeliefHaveItsValues) {
  Rng rng(16);
  const BeliefLayout layout({Model(2), Model(4), Model(2)});
  BeliefSet beliefs(&layout, 7);
  for (int r = 0; r < 7; ++r)
    for (int k = 0; k < 3; ++k) {
      beliefs.Omega(r, k) = RandomSpd(layout.dim(k), &rng);
      beliefs.Xi(r, k) = RandomVector(layout.dim(k), &rng);
    }
  // Target 0: rows 1 to 5 hold row 0's belief; target 1: rows 3 and 4
  // hold row 2's; target 2: row 6 holds row 5's but for the sign of a
  // zero (another bit pattern, the same number).
  for (int r = 1; r < 6; ++r) beliefs.CopyRow(r, beliefs, 0);
  for (int r = 1; r < 6; ++r) {
    beliefs.Omega(r, 1) = beliefs.Omega(r == 1 ? 1 : 2, 1);
    beliefs.Xi(r, 1) = beliefs.Xi(r == 1 ? 1 : 2, 1);
    beliefs.Omega(r, 2) = RandomSpd(2, &rng);
    beliefs.Xi(r, 2) = RandomVector(2, &rng);
  }
  beliefs.Omega(5, 2)(0, 1) = beliefs.Omega(5, 2)(1, 0) = 0.0;
  beliefs.Omega(6, 2) = beliefs.Omega(5, 2);
  beliefs.Omega(6, 2)(0, 1) = -0.0;
  beliefs.Xi(6, 2) = beliefs.Xi(5, 2);
  BeliefDigest serial, split;
  serial.Compute(beliefs);
  // The later part first: a row must not take values from another part,
  // which another thread may not have written yet.
  split.Compute(beliefs, [](int n, const RangeTask& f) {
    f(3, n, 1);
    f(0, 3, 0);
  });
  for (const BeliefDigest* d : {&serial, &split})
    for (int r = 0; r < 7; ++r)
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(d->LogDet(r, k), beliefs.LogDetCovariance(r, k)) << r << k;
        EXPECT_EQ(d->Mean(r, k), beliefs.PositionMean(r, k)) << r << k;
      }
}

}  // namespace
}  // namespace aia
