// Micro-benchmarks of the per-step kernels (Google Benchmark):
//   build/benchmarks/aia_micro_bench [--benchmark_filter=Fuse]
// Whole decision steps are timed by `aia bench`.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "aia/comm/graph.h"
#include "aia/commands/bench.h"
#include "aia/commands/eval.h"
#include "aia/estimation/filter.h"
#include "aia/planning/expert.h"
#include "aia/runtime/episode.h"
#include "aia/runtime/instance.h"
#include "aia/runtime/mission.h"
#include "aia/sim/simulation.h"

namespace aia {
namespace {

// DKF fusion of N robots x N static targets over a full graph with packet
// loss, a few measurements per robot: the episode's form (DkfWeights; the
// beliefs shared, docs/design.md, Estimation).
void BM_Fuse(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::vector<TargetModel> models(n);
  BeliefLayout layout(models);
  BeliefSet predicted(&layout, n), fused(&layout, n);
  std::vector<Eigen::VectorXd> means(n, Eigen::Vector2d(5, 5));
  std::vector<Eigen::MatrixXd> covs(n, Eigen::Matrix2d::Identity());
  predicted.SetPrior(means, covs);
  fused.SetPrior(means, covs);
  CommParams cp;
  cp.packet_loss_lambda = 1.0;
  CommNetwork comm(cp, n, {}, 1);
  std::vector<Vec2> pos(n, Vec2(1, 1));
  comm.Update(0, pos);
  DkfWeights w;
  MakeDkfWeights(comm.AllNeighbors(), 0.75, &w);
  std::vector<std::vector<Measurement>> z(n);
  for (int i = 0; i < n; ++i)
    for (int k = i % 7; k < n; k += 17)
      z[i].push_back({k, Vec2(0.5, 0.5), 50.0});
  for (auto _ : state) {
    Fuse(predicted, w, z, pos, &fused);
    benchmark::DoNotOptimize(fused.Block(0, 0));
  }
}
BENCHMARK(BM_Fuse)->Arg(10)->Arg(80)->Arg(1000)->Unit(benchmark::kMicrosecond);

// The expert's solve from the initial state of a generated world.
void BM_ExpertSolve(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  Scenario s = GeneratedScenario(n, n, 1);
  s.policy.name = "random";
  auto episode = MakeEpisode(s, AllPolicies());
  const SamplingProblem problem = ExpertProblem(episode->Context());
  SamplingTree tree;
  SamplingParams params;
  for (auto _ : state) {
    Rng rng(1, "policy.expert");
    benchmark::DoNotOptimize(tree.Solve(problem, params, rng).depth);
  }
}
BENCHMARK(BM_ExpertSolve)
    ->Arg(10)
    ->Arg(40)
    ->Arg(80)
    ->Unit(benchmark::kMillisecond);

// One decision step of the random policy, physics included.
void BM_DecisionStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  Scenario s = GeneratedScenario(n, n, 1);
  s.policy.name = "random";
  s.mission.stop_at_success = false;
  s.mission.max_steps = 1 << 30;
  auto episode = MakeEpisode(s, AllPolicies());
  for (auto _ : state) episode->Step();
}
BENCHMARK(BM_DecisionStep)->Arg(10)->Arg(80)->Unit(benchmark::kMillisecond);

// One physics step (StepPhysics: the robots' controllers, then mj_step with
// its contact budget) of a generated world that grows with the team as those
// of tools/bench_scale.py: robots at rest, which is what mujoco-testspeed
// times on the same model (passive dynamics from the start), and robots
// driven to a random lattice neighbour, a new one every decision step's
// worth of physics (50 steps, 0.25 s, for point robots; 300, 1.5 s, for
// diff_drive robots), as decisions drive them (they touch). Arguments:
// robots, driven, model (0 point, 1 diff_drive).
Scenario GrowingScenario(int n, bool wheeled) {
  Scenario s = GeneratedScenario(n, n, 1);
  const double side = 20.0 * std::sqrt(std::max(n, 40) / 40.0);
  s.workspace.size = Vec2(side, side);
  s.workspace.obstacles.random->count =
      static_cast<int>(std::lround(0.075 * side * side));
  if (wheeled) s.robots.model = RobotModel::kDiffDrive;
  return s;
}

std::shared_ptr<const Instance> PhysicsWorld(int n, bool wheeled) {
  return BuildInstance(GrowingScenario(n, wheeled));
}

void BM_PhysicsStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const bool driven = state.range(1) != 0;
  const bool wheeled = state.range(2) != 0;
  const std::shared_ptr<const Instance> instance = PhysicsWorld(n, wheeled);
  const Lattice& lattice = instance->world.map.lattice();
  Simulation sim(instance->physics);
  Rng rng(1, "bench.physics");
  const long period = wheeled ? 300 : 50;
  long steps = 0;
  for (auto _ : state) {
    if (driven && steps % period == 0) {
      for (int i = 0; i < n; ++i) {
        const int p = lattice.NearestFree(sim.RobotPosition(i));
        if (p < 0) continue;
        const int q = lattice.Next(p, kMoves[rng.UniformInt(kNumMoves)]);
        if (q >= 0) sim.SetWaypoint(i, lattice.Point(q));
      }
    }
    sim.StepPhysics();
    ++steps;
  }
  state.counters["contacts"] =
      static_cast<double>(sim.contacts_summed()) / std::max(1L, sim.mj_steps());
}
BENCHMARK(BM_PhysicsStep)
    ->ArgsProduct({{80, 1000}, {0, 1}, {0}})
    ->ArgsProduct({{10, 80}, {0, 1}, {1}})
    ->Unit(benchmark::kMillisecond);

// mj_step alone on the same models, robots at rest: mujoco-testspeed's loop,
// against which BM_PhysicsStep's at-rest figure shows what the controllers
// and the contact budget's bookkeeping add. Arguments: robots, model.
void BM_MjStepAlone(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const std::shared_ptr<const Instance> instance =
      PhysicsWorld(n, state.range(1) != 0);
  const mjModel* m = instance->physics->model();
  MjDataPtr d(mj_makeData(m));
  for (auto _ : state) mj_step(m, d.get());
}
BENCHMARK(BM_MjStepAlone)
    ->ArgsProduct({{80, 1000}, {0}})
    ->ArgsProduct({{10, 80}, {1}})
    ->Unit(benchmark::kMillisecond);

// One decision step of the default policy (igbnet, its shipped model and
// coordination) in the worlds of BM_PhysicsStep, one policy thread: what
// regressed 10x at 1000 robots before any benchmark caught it (issue 36).
// The counter policy_ms is the policy's share of a step. Arguments: robots,
// decisions (0 lockstep; 1 async, where a step is one round: the robots
// whose moves ended decide, which redid the whole team's work each round
// until 2026-12-07).
void BM_DefaultPolicyStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  Scenario s = GrowingScenario(n, false);
  if (state.range(1) != 0) s.mission.decisions = Decisions::kAsync;
  s.policy.name = "igbnet";
  s.mission.stop_at_success = false;
  s.mission.max_steps = 1 << 30;
  auto episode = MakeEpisode(s, AllPolicies());
  episode->Step();  // past the first step's one-off work
  const double before = episode->times().policy;
  long steps = 0;
  for (auto _ : state) {
    episode->Step();
    ++steps;
  }
  state.counters["policy_ms"] =
      1e3 * (episode->times().policy - before) / std::max(1L, steps);
}
BENCHMARK(BM_DefaultPolicyStep)
    ->ArgsProduct({{80, 1000}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace aia

BENCHMARK_MAIN();
