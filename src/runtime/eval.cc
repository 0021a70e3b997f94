#include "aia/runtime/eval.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "aia/core/error.h"
#include "aia/core/io.h"
#include "aia/runtime/bench.h"
#include "aia/runtime/mission.h"
#include "aia/runtime/plan_command.h"

namespace aia {
namespace {

constexpr const char* kHeader =
    "size,seed,policy,success,flowtime,fstar,wall_s";

std::string FormatRow(const EvalRow& r) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%s,%llu,%s,%d,%s,%d,%.4f\n", r.size.c_str(),
                static_cast<unsigned long long>(r.seed), r.policy.c_str(),
                r.success ? 1 : 0,
                r.flowtime >= 0 ? std::to_string(r.flowtime).c_str() : "",
                r.fstar, r.wall_s);
  return buf;
}

bool ParseRow(const std::string& line, EvalRow* r) {
  std::vector<std::string> f;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) f.push_back(cell);
  if (line.size() && line.back() == ',') f.push_back("");
  if (f.size() != 7) return false;
  try {
    r->size = f[0];
    r->seed = std::stoull(f[1]);
    r->policy = f[2];
    if (f[3] != "0" && f[3] != "1") return false;
    r->success = f[3] == "1";
    r->flowtime = f[4].empty() ? -1 : std::stoi(f[4]);
    r->fstar = std::stoi(f[5]);
    r->wall_s = std::stod(f[6]);
  } catch (const std::exception&) {
    return false;
  }
  return !r->size.empty() && !r->policy.empty();
}

// Horizon and denominator of an instance: 3 F* steps, with F* = 0 (targets
// all localized at the start) counted as 1 so that the ratio is defined.
int Horizon(int fstar) { return 3 * std::max(fstar, 1); }

}  // namespace

std::vector<EvalRow> ReadRuns(const std::string& path) {
  std::vector<EvalRow> rows;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    EvalRow r;
    if (line == kHeader || line.empty()) continue;
    if (ParseRow(line, &r)) rows.push_back(r);
  }
  return rows;
}

std::string SummaryCsv(const std::vector<EvalRow>& rows,
                       const std::vector<std::string>& sizes,
                       const std::vector<std::string>& policies) {
  std::string out =
      "size,policy,instances,success_rate,flowtime_increase,mean_flowtime,mean_"
      "fstar,"
      "no_expert_plan\n";
  for (const auto& size : sizes) {
    for (const auto& policy : policies) {
      int n = 0, ok = 0, no_plan = 0;
      double inc = 0.0, flow = 0.0, fstar = 0.0;
      for (const EvalRow& r : rows) {
        if (r.size != size || r.policy != policy) continue;
        if (r.fstar < 0) {
          ++no_plan;
          continue;
        }
        ++n;
        const int denom = std::max(r.fstar, 1);
        const int f = r.success ? r.flowtime : Horizon(r.fstar);
        ok += r.success ? 1 : 0;
        inc += static_cast<double>(f - r.fstar) / denom;
        flow += f;
        fstar += r.fstar;
      }
      char buf[256];
      if (n == 0) {
        std::snprintf(buf, sizeof(buf), "%s,%s,0,,,,,%d\n", size.c_str(),
                      policy.c_str(), no_plan);
      } else {
        std::snprintf(buf, sizeof(buf), "%s,%s,%d,%.4f,%.4f,%.3f,%.3f,%d\n",
                      size.c_str(), policy.c_str(), n,
                      static_cast<double>(ok) / n, inc / n, flow / n, fstar / n,
                      no_plan);
      }
      out += buf;
    }
  }
  return out;
}

int RunEval(const EvalOptions& o) {
  if (o.seeds < 1)
    throw InputError("command line", 0, "--seeds", "must be at least 1");
  if (o.threads < 0)
    throw InputError("command line", 0, "--threads", "must be >= 0");
  if (o.out_dir.empty())
    throw InputError("command line", 0, "--out",
                     "an output folder is required");
  const PolicyRegistry registry = AllPolicies();
  std::vector<std::string> policies = o.policies;
  if (policies.empty()) {
    for (const auto& name : registry.Names())
      if (name != "expert") policies.push_back(name);
  }
  for (const auto& p : policies) {
    if (!registry.Has(p))
      throw InputError(
          "command line", 0, "--policies",
          "unknown policy '" + p + "' (valid: " + registry.NameList() + ")");
  }
  std::vector<std::pair<int, int>> dims;
  for (const auto& s : o.sizes) dims.push_back(ParseSize(s, "--sizes"));

  MakeOutputDir(o.out_dir, "--out");
  const std::string runs_path = o.out_dir + "/runs.csv";
  // Resume: keep the rows already there, rewritten cleanly (a row cut short
  // by an interruption is dropped and run again).
  std::vector<EvalRow> rows = ReadRuns(runs_path);
  std::set<std::tuple<std::string, std::uint64_t, std::string>> done;
  for (const auto& r : rows) done.insert({r.size, r.seed, r.policy});
  {
    std::string text = std::string(kHeader) + "\n";
    for (const auto& r : rows) text += FormatRow(r);
    WriteFileAtomic(runs_path, text);
  }

  struct Instance {
    size_t size_index;
    std::uint64_t seed;
    std::vector<std::string> todo;
  };
  std::vector<Instance> work;
  int total_runs = 0;
  for (size_t si = 0; si < o.sizes.size(); ++si) {
    for (int s = 0; s < o.seeds; ++s) {
      Instance inst{si, o.seed_base + static_cast<std::uint64_t>(s), {}};
      for (const auto& p : policies)
        if (!done.count({o.sizes[si], inst.seed, p})) inst.todo.push_back(p);
      total_runs += static_cast<int>(inst.todo.size());
      if (!inst.todo.empty()) work.push_back(std::move(inst));
    }
  }
  std::printf(
      "aia eval: %zu sizes x %d seeds x %zu policies; %zu rows already done, "
      "%d to run\n",
      o.sizes.size(), o.seeds, policies.size(), rows.size(), total_runs);
  std::fflush(stdout);

  const int fd = ::open(runs_path.c_str(), O_WRONLY | O_APPEND);
  if (fd < 0) throw std::runtime_error("cannot append to " + runs_path);
  std::mutex mu;
  std::atomic<size_t> next{0};
  int finished = 0;
  ProgressLine progress(o.progress);
  std::string first_error;
  auto worker = [&]() {
    while (true) {
      const size_t w = next.fetch_add(1);
      if (w >= work.size()) return;
      const Instance& inst = work[w];
      try {
        const auto [n, m] = dims[inst.size_index];
        Scenario scenario = GeneratedScenario(n, m, inst.seed);
        const SamplingPlan plan = PlanFromStart(scenario);
        const int fstar = plan.found ? plan.depth : -1;
        for (const auto& policy : inst.todo) {
          EvalRow row;
          row.size = o.sizes[inst.size_index];
          row.seed = inst.seed;
          row.policy = policy;
          row.fstar = fstar;
          if (fstar >= 0) {
            const auto t0 = std::chrono::steady_clock::now();
            Scenario s = scenario;
            s.policy.name = policy;
            s.mission.max_steps = Horizon(fstar);
            auto episode = MakeEpisode(s, registry);
            while (!episode->done()) episode->Step();
            row.success = episode->success();
            row.flowtime = episode->flowtime();
            row.wall_s = std::chrono::duration<double>(
                             std::chrono::steady_clock::now() - t0)
                             .count();
          }
          const std::string line = FormatRow(row);
          std::lock_guard<std::mutex> lock(mu);
          if (::write(fd, line.data(), line.size()) !=
              static_cast<ssize_t>(line.size()))
            throw std::runtime_error("cannot append to " + runs_path);
          rows.push_back(row);
          ++finished;
          char buf[200];
          std::snprintf(buf, sizeof(buf),
                        "[aia eval] %d/%d runs  (last: %s seed %llu %s)",
                        finished, total_runs, row.size.c_str(),
                        static_cast<unsigned long long>(row.seed),
                        row.policy.c_str());
          progress.Update(buf);
        }
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mu);
        if (first_error.empty()) first_error = e.what();
        next = work.size();  // stop handing out work
      }
    }
  };
  int threads = o.threads > 0
                    ? o.threads
                    : static_cast<int>(std::thread::hardware_concurrency());
  threads = std::max(
      1, std::min<int>(threads,
                       static_cast<int>(std::max<size_t>(work.size(), 1))));
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  progress.Finish();
  ::fsync(fd);
  ::close(fd);
  if (!first_error.empty()) throw std::runtime_error(first_error);

  // Canonical order, so the files do not depend on the thread count.
  std::map<std::string, size_t> size_rank, policy_rank;
  for (size_t i = 0; i < o.sizes.size(); ++i) size_rank.emplace(o.sizes[i], i);
  for (size_t i = 0; i < policies.size(); ++i)
    policy_rank.emplace(policies[i], i);
  auto rank = [](const std::map<std::string, size_t>& m, const std::string& k) {
    const auto it = m.find(k);
    return it == m.end() ? m.size() : it->second;
  };
  std::stable_sort(
      rows.begin(), rows.end(), [&](const EvalRow& a, const EvalRow& b) {
        return std::make_tuple(rank(size_rank, a.size), a.size, a.seed,
                               rank(policy_rank, a.policy), a.policy) <
               std::make_tuple(rank(size_rank, b.size), b.size, b.seed,
                               rank(policy_rank, b.policy), b.policy);
      });
  std::string text = std::string(kHeader) + "\n";
  for (const auto& r : rows) text += FormatRow(r);
  WriteFileAtomic(runs_path, text);
  std::vector<EvalRow> in_range;
  for (const auto& r : rows)
    if (r.seed >= o.seed_base &&
        r.seed < o.seed_base + static_cast<std::uint64_t>(o.seeds))
      in_range.push_back(r);
  const std::string summary = SummaryCsv(in_range, o.sizes, policies);
  WriteFileAtomic(o.out_dir + "/summary.csv", summary);
  std::printf("%s", summary.c_str());
  std::printf("wrote %s and %s/summary.csv\n", runs_path.c_str(),
              o.out_dir.c_str());
  return 0;
}

}  // namespace aia
