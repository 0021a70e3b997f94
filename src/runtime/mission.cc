#include "aia/runtime/mission.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "aia/core/clock.h"
#include "aia/core/error.h"
#include "aia/core/io.h"
#include "aia/learning/network.h"
#include "aia/scenario/loader.h"

namespace aia {
namespace {

long Sum(const std::vector<long>& counts) {
  long sum = 0;
  for (const long c : counts) sum += c;
  return sum;
}

constexpr char kEffectiveHeader[] =
    "# The effective scenario of this result: every key with its value,\n"
    "# defaults filled in, command-line overrides and the policy's parameters\n"
    "# applied. `aia run` reads it back to the same mission.\n";

// policy.model (or model_sha256) given to a policy that reads no model
// changes nothing: a warning, unless the key is the file's and the command
// line switched the policy (a file's model for igbnet run with --policy
// greedy says nothing).
void WarnUnreadModel(const PolicySpec& policy, Scenario* scenario) {
  if (policy.model_file() != nullptr) return;
  const auto origin = [&](const std::string& key) {
    const auto it = scenario->sources.find(key);
    return it == scenario->sources.end() ? std::string() : it->second.origin;
  };
  for (const char* key : {"policy.model", "policy.model_sha256"}) {
    if (!scenario->sources.count(key) ||
        (origin(key).empty() && !origin("policy.name").empty()))
      continue;
    scenario->warnings.push_back(
        scenario
            ->ErrorAt(key, "policy " + scenario->policy.name +
                               " reads no model: it changes nothing")
            .Format());
  }
}

}  // namespace

std::vector<Override> CommandOverrides::ToOverrides(
    const PolicyRegistry& registry) const {
  std::vector<Override> out;
  if (policy) {
    if (!registry.Has(*policy))
      throw InputError::Flag("--policy", registry.UnknownPolicy(*policy));
    out.push_back({"--policy", "policy.name", *policy});
  }
  if (seed) out.push_back({"--seed", "seed", std::to_string(*seed)});
  if (max_steps)
    out.push_back(
        {"--max-steps", "mission.max_steps", std::to_string(*max_steps)});
  out.insert(out.end(), flags.begin(), flags.end());
  const std::size_t given = out.size();
  for (Override& o : ParseSetFlags(sets)) {
    for (std::size_t i = 0; i < given; ++i)
      RefuseSetOfFlagKey(o, out[i].path, out[i].flag);
    out.push_back(std::move(o));
  }
  return out;
}

std::unique_ptr<Episode> MakeEpisode(const Scenario& scenario,
                                     const PolicyRegistry& registry) {
  return std::make_unique<Episode>(BuildInstance(scenario),
                                   registry.Resolve(scenario)->Create());
}

PreparedMission PrepareMission(Scenario scenario,
                               const PolicyRegistry& registry) {
  PreparedMission m;
  m.started = std::chrono::steady_clock::now();
  // One mission in the process: a learned policy renders and infers on every
  // core (its results do not depend on the thread count; eval's workers
  // keep one thread each).
  SetPolicyThreads(static_cast<int>(std::thread::hardware_concurrency()));
  m.policy = registry.Resolve(scenario);
  WarnUnreadModel(*m.policy, &scenario);
  m.instance = BuildInstance(scenario);
  ReportWarnings(scenario);
  m.scenario = std::move(scenario);
  return m;
}

Scenario EffectiveScenario(const PreparedMission& mission) {
  Scenario s = mission.scenario;
  s.policy.params = mission.policy->Params();
  // The async-only keys as the episode takes them where none is given, so
  // that every key is written with the value it ran with.
  if (s.mission.decisions == Decisions::kAsync) {
    if (!s.mission.avoidance) s.mission.avoidance = kDefaultAvoidance;
    if (!s.sensor.rate) s.sensor.rate = DefaultSensorRate(s.robots.model);
  }
  // The model as loaded: where it was (the default resolved) and its
  // content, so that a repeat refuses a retrained file.
  if (const FileIdentity* model = mission.policy->model_file()) {
    s.policy.model = model->path;
    s.policy.model_sha256 = model->sha256;
  } else {
    // A policy that reads none (the file's igbnet switched by --policy):
    // kept, the model would be warned about on every repeat.
    s.policy.model.clear();
    s.policy.model_sha256.reset();
  }
  return s;
}

std::vector<InputFile> MissionInputs(const Scenario& scenario,
                                     const PolicySpec* policy) {
  std::vector<InputFile> in;
  if (!scenario.file.empty())
    in.push_back({scenario.file, "the input scenario"});
  if (!scenario.workspace.obstacles.map.empty())
    in.push_back({scenario.workspace.obstacles.map,
                  "the scenario's map image (workspace.obstacles.map)"});
  if (policy && policy->model_file())
    in.push_back(
        {policy->model_file()->path, "the policy's model file (policy.model)"});
  return in;
}

std::vector<std::string> MissionFileNames() {
  return {"summary.json", "trace.csv", "estimate.csv", "effective.yaml",
          "diagnostics.json"};
}

MissionSummary Summarize(const Episode& e, double wall_s) {
  MissionSummary s;
  s.scenario = e.scenario().name;
  s.policy = std::string(e.policy().name());
  s.seed = e.scenario().seed;
  s.robots = e.world().NumRobots();
  s.targets = e.world().NumTargets();
  s.success = e.success();
  s.flowtime = e.flowtime();
  s.steps = e.step();
  s.invalid_moves = e.invalid_moves();
  s.localized_share =
      static_cast<double>(e.localized_steps()) / (e.filter_step() + 1);
  s.wall_s = wall_s;
  return s;
}

std::string SummaryJson(const MissionSummary& s, const Episode& e) {
  nlohmann::ordered_json j;
  j["scenario"] = s.scenario;
  j["scenario_file"] = e.scenario().file;
  j["policy"] = s.policy;
  j["seed"] = s.seed;
  j["robots"] = s.robots;
  j["targets"] = s.targets;
  j["success"] = s.success;
  j["flowtime"] = s.flowtime >= 0 ? nlohmann::ordered_json(s.flowtime)
                                  : nlohmann::ordered_json();
  j["steps"] = s.steps;
  j["robot_model"] = EnumNameOf(e.scenario().robots.model);
  j["mission_seconds"] = e.mission_seconds();
  j["robot_stalls"] = Sum(e.sim().robot_stalls());
  j["robot_timeouts"] = Sum(e.sim().robot_timeouts());
  j["max_steps"] = e.mission().max_steps;
  j["eps"] = e.mission().eps;
  j["invalid_moves"] = s.invalid_moves;
  j["localized_share"] = s.localized_share;
  j["localized_at_end"] = e.NumLocalized();
  std::vector<double> final_det;
  for (int k = 0; k < e.world().NumTargets(); ++k)
    final_det.push_back(e.MinDet(k));
  j["final_min_det"] = final_det;
  std::vector<int> failed;
  for (int i = 0; i < e.world().NumRobots(); ++i)
    if (!e.comm().Active(i)) failed.push_back(i);
  j["failed_robots"] = failed;
  j["wall_s"] = s.wall_s;
  // Only for a mission stopped by Ctrl-C, whose steps end early.
  if (e.interrupted()) j["interrupted"] = true;
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string DiagnosticsJson(const Episode& e, const MoveObserver& moves,
                            const EstimateObserver& estimate, double wall_s) {
  nlohmann::ordered_json d;
  nlohmann::ordered_json statuses;
  for (int s = 0; s < kNumPolicyStatuses; ++s)
    statuses[std::string(PolicyStatusName(static_cast<PolicyStatus>(s)))] =
        e.stats().statuses[s];
  d["policy_status"] = statuses;
  nlohmann::ordered_json counters = nlohmann::ordered_json::object();
  for (const auto& [name, count] : e.policy().Counters())
    counters[name] = count;
  d["policy_counters"] = counters;
  const EpisodeStats& st = e.stats();
  d["physics"] = {{"steps", e.step()},
                  {"timeouts", st.physics_timeouts},
                  {"stalled_steps", st.stalled_steps},
                  {"substeps", st.substeps},
                  {"sim_seconds", st.sim_seconds},
                  {"mission_seconds", e.mission_seconds()},
                  // Per robot: steps it ended stalled short of its
                  // waypoint, and steps whose timeout found it on its way.
                  {"robot_stalls", e.sim().robot_stalls()},
                  {"robot_timeouts", e.sim().robot_timeouts()},
                  // Per robot: moves (stays included) it completed; in
                  // lockstep each active robot's are the steps.
                  {"robot_decisions", e.decisions()}};
  // Where the robots' time went (robot-seconds): what real motion costs.
  const Simulation::TimeUse& use = e.sim().time_use();
  d["physics"]["robot_seconds"] = {
      {"driving", use.driving}, {"turning", use.turning},
      {"blocked", use.blocked}, {"arrived", use.arrived},
      {"staying", use.staying}, {"yielding", use.yielding}};
  // MuJoCo's memory and warnings (sim/simulation.h): a warning other than a
  // handled contact overflow means the physics went wrong somewhere.
  const PhysicsMemoryStats mem = e.sim().memory();
  d["physics"]["memory"] = {{"nconmax", mem.nconmax},
                            {"njmax", mem.njmax},
                            {"grows", mem.grows},
                            {"max_contacts", mem.max_contacts},
                            {"max_constraints", mem.max_constraints},
                            {"max_stack", mem.max_stack},
                            {"nstack", mem.nstack},
                            {"data_mib", mem.data_bytes / (1 << 20)}};
  nlohmann::ordered_json warnings = nlohmann::ordered_json::object();
  for (int w = 0; w < mjNWARNING; ++w)
    if (e.sim().warnings()[w] > 0)
      warnings[MujocoWarningName(w)] = e.sim().warnings()[w];
  d["physics"]["mujoco_warnings"] = warnings;
  d["moves"] = {{"total", moves.moves()},
                {"reversals", moves.reversals()},
                {"longest_reversal_run", moves.longest_reversal_run()},
                {"stays", moves.stays()}};
  nlohmann::ordered_json per_target = nlohmann::ordered_json::array();
  for (int k = 0; k < estimate.num_targets(); ++k)
    per_target.push_back(
        {{"rmse_m", estimate.rmse(k)}, {"mean_nees", estimate.mean_nees(k)}});
  d["estimate"] = {{"rmse_m", estimate.rmse()},
                   {"mean_nees", estimate.mean_nees()},
                   {"targets", per_target}};
  const PhaseTimes& t = e.times();
  d["wall_seconds"] = {{"physics", t.physics}, {"sensing", t.sensing},
                       {"fusion", t.fusion},   {"policy", t.policy},
                       {"steps", t.total},     {"total", wall_s}};
  return d.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

bool TraceHasRobotColumns(TraceMode mode, int num_robots) {
  return mode == TraceMode::kFull ||
         (mode == TraceMode::kAuto && num_robots <= kTraceFullRobots);
}

MissionRunner::MissionRunner(const PreparedMission& mission, std::string prefix,
                             std::string label, bool progress,
                             std::function<std::string()> progress_extra,
                             TraceMode trace)
    : mission_(mission), prefix_(std::move(prefix)) {
  episode_ =
      std::make_unique<Episode>(mission.instance, mission.policy->Create());
  const int n = episode_->world().NumRobots();
  trace_ = std::make_unique<TraceObserver>(prefix_ + "trace.csv", n,
                                           TraceHasRobotColumns(trace, n),
                                           episode_->async());
  estimate_ = std::make_unique<EstimateObserver>(prefix_ + "estimate.csv");
  progress_ = std::make_unique<ProgressObserver>(std::move(label), progress,
                                                 std::move(progress_extra));
  episode_->AddObserver(trace_.get());
  episode_->AddObserver(estimate_.get());
  moves_ = std::make_unique<MoveObserver>();
  episode_->AddObserver(progress_.get());
  episode_->AddObserver(moves_.get());
}

MissionRunner::~MissionRunner() = default;

MissionSummary MissionRunner::Run() {
  Episode& e = *episode_;
  e.Run();
  const MissionSummary summary = Summarize(e, SecondsSince(mission_.started));
  // Exits 0 all the same: the files are written and diagnostics.json counts
  // the warnings (physics.mujoco_warnings); no setting can be refused ahead,
  // since whether a motor is too strong (or too weak to arrive) depends on
  // the contacts it meets.
  const std::string what =
      e.scenario().name + ", seed " + std::to_string(e.scenario().seed);
  std::fputs(EndOfMissionWarnings(e, moves_->moves(), what).c_str(), stderr);

  WriteFileAtomic(prefix_ + "effective.yaml",
                  EffectiveYaml(EffectiveScenario(mission_), kEffectiveHeader));

  WriteFileAtomic(prefix_ + "diagnostics.json",
                  DiagnosticsJson(e, *moves_, *estimate_, summary.wall_s));
  return summary;
}

}  // namespace aia
