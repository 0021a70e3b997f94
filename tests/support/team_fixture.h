// A team at its starts with prior beliefs, for planner tests (header-only:
// the support library does not link the planners).
#ifndef AIA_TESTS_SUPPORT_TEAM_FIXTURE_H_
#define AIA_TESTS_SUPPORT_TEAM_FIXTURE_H_

#include <string>
#include <vector>

#include "aia/comm/graph.h"
#include "aia/estimation/belief.h"
#include "aia/planning/policy.h"
#include "aia/world/world.h"
#include "support/test_support.h"

namespace aia::testing {

// A world, the prior beliefs (one row per robot and the centralized row) and
// a communication graph (full by default). Context() is the whole team's,
// the centralized belief included (what the expert is given). Copies share the
// original's belief layout, so the original must outlive them.
struct TeamFixture {
  Scenario scenario;
  World world;
  SensorModel sensor;
  BeliefLayout layout;
  BeliefSet beliefs, central;
  CommNetwork comm;
  std::vector<int> positions;

  explicit TeamFixture(const std::string& yaml, CommParams cp = {})
      : scenario(ScenarioFromYaml(yaml)) {
    world = World::Build(scenario);
    std::vector<TargetModel> models;
    std::vector<Eigen::VectorXd> means;
    std::vector<Eigen::MatrixXd> covs;
    for (const TargetPrior& p : world.priors) {
      models.push_back(p.model);
      means.push_back(p.mean);
      covs.push_back(p.cov);
    }
    layout = BeliefLayout(models);
    beliefs = BeliefSet(&layout, world.NumRobots());
    central = BeliefSet(&layout, 1);
    beliefs.SetPrior(means, covs);
    central.SetPrior(means, covs);
    comm = CommNetwork(cp, world.NumRobots(), {}, 1);
    positions = world.robot_starts;
    std::vector<Vec2> p;
    for (int idx : positions) p.push_back(world.map.lattice().Point(idx));
    comm.Update(0, p);
  }
  DecisionContext Context() const {
    DecisionContext c;
    c.map = &world.map;
    c.sensor = &sensor;
    c.eps = scenario.mission.eps;
    c.robot_lattice = &positions;
    c.comm = &comm;
    c.beliefs = &beliefs;
    c.central = &central;
    return c;
  }
};

}  // namespace aia::testing

#endif  // AIA_TESTS_SUPPORT_TEAM_FIXTURE_H_
