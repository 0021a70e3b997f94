#include "aia/runtime/mission.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "aia/core/error.h"
#include "aia/core/io.h"
#include "aia/scenario/loader.h"

namespace aia {

PolicyRegistry AllPolicies() { return BuiltinPolicies(); }

void ApplyOverrides(const ScenarioOverrides& o, const PolicyRegistry& registry,
                    Scenario* s) {
  if (o.policy) {
    if (!registry.Has(*o.policy))
      throw InputError("command line", 0, "--policy",
                       "unknown policy '" + *o.policy +
                           "' (valid: " + registry.NameList() + ")");
    // Parameters in the file belong to the policy it named.
    if (*o.policy != s->policy.name) s->policy.params.clear();
    s->policy.name = *o.policy;
  }
  if (o.seed) s->seed = *o.seed;
  if (o.max_steps) {
    if (*o.max_steps < 1)
      throw InputError("command line", 0, "--max-steps", "must be at least 1");
    s->mission.max_steps = *o.max_steps;
  }
}

void MakeOutputDir(const std::string& dir, const std::string& flag) {
  if (dir.empty()) return;
  try {
    MakeDirs(dir);
  } catch (const std::exception& e) {
    throw InputError("command line", 0, flag, e.what());
  }
}

std::unique_ptr<Episode> MakeEpisode(const Scenario& scenario,
                                     const PolicyRegistry& registry) {
  return std::make_unique<Episode>(
      scenario, registry.Create(scenario.policy.name, scenario));
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
  s.localized_share = static_cast<double>(e.localized_steps()) / (e.step() + 1);
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
  j["max_steps"] = e.scenario().mission.max_steps;
  j["eps"] = e.scenario().mission.eps;
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
  return j.dump(2) + "\n";
}

struct TraceWriter::Impl {
  AtomicFile file;
  std::string row;
  explicit Impl(const std::string& path) : file(path) {}
};

TraceWriter::TraceWriter(const std::string& path, int num_robots)
    : impl_(std::make_shared<Impl>(path)) {
  std::string header = "step,target,min_det";
  for (int i = 0; i < num_robots; ++i) header += ",det_r" + std::to_string(i);
  header += "\n";
  std::fputs(header.c_str(), impl_->file.get());
}

void TraceWriter::Write(const Episode& e) {
  const int n = e.world().NumRobots();
  char buf[64];
  for (int k = 0; k < e.world().NumTargets(); ++k) {
    std::string& row = impl_->row;
    row.clear();
    std::snprintf(buf, sizeof(buf), "%d,%d,%.6e", e.step(), k, e.MinDet(k));
    row += buf;
    for (int i = 0; i < n; ++i) {
      std::snprintf(buf, sizeof(buf), ",%.6e", e.Det(i, k));
      row += buf;
    }
    row += '\n';
    std::fwrite(row.data(), 1, row.size(), impl_->file.get());
  }
}

void TraceWriter::Commit() { impl_->file.Commit(); }

ProgressLine::ProgressLine(bool enabled)
    : enabled_(enabled && ::isatty(STDERR_FILENO)) {}

void ProgressLine::Update(const std::string& text) {
  if (!enabled_) return;
  std::string line = "\r" + text;
  if (text.size() < last_width_)
    line += std::string(last_width_ - text.size(), ' ');
  last_width_ = text.size();
  std::fputs(line.c_str(), stderr);
  std::fflush(stderr);
}

void ProgressLine::Finish() {
  if (enabled_ && last_width_ > 0) std::fputs("\n", stderr);
  last_width_ = 0;
}

MissionSummary RunMission(const RunOptions& options) {
  const PolicyRegistry registry = AllPolicies();
  Scenario scenario = LoadScenario(options.scenario_path);
  ApplyOverrides(options.overrides, registry, &scenario);
  std::string out = options.out_dir;
  if (out.empty())
    out = "renders/" +
          std::filesystem::path(options.scenario_path).stem().string();

  const auto t0 = std::chrono::steady_clock::now();
  auto episode = MakeEpisode(scenario, registry);
  MakeOutputDir(out, "--out");
  TraceWriter trace(out + "/trace.csv", episode->world().NumRobots());
  trace.Write(*episode);
  ProgressLine progress(options.progress);
  const int m = episode->world().NumTargets();
  while (!episode->done()) {
    episode->Step();
    trace.Write(*episode);
    char buf[160];
    std::snprintf(buf, sizeof(buf), "[aia run] %s  step %d/%d  localized %d/%d",
                  std::string(episode->policy().name()).c_str(),
                  episode->step(), scenario.mission.max_steps,
                  episode->NumLocalized(), m);
    progress.Update(buf);
  }
  progress.Finish();
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
          .count();
  trace.Commit();
  const MissionSummary summary = Summarize(*episode, wall);
  WriteFileAtomic(out + "/summary.json", SummaryJson(summary, *episode));
  std::printf(
      "%s: policy %s, seed %llu: %s in %d steps (%d robots, %d targets, %ld "
      "invalid moves), "
      "%.2f s -> %s/\n",
      scenario.name.c_str(), summary.policy.c_str(),
      static_cast<unsigned long long>(summary.seed),
      summary.success ? "success" : "no success",
      summary.success ? summary.flowtime : summary.steps, summary.robots,
      summary.targets, summary.invalid_moves, wall, out.c_str());
  return summary;
}

}  // namespace aia
