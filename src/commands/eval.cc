#include "aia/commands/eval.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "aia/commands/plan_command.h"
#include "aia/commands/ranks.h"
#include "aia/core/check.h"
#include "aia/core/error.h"
#include "aia/core/interrupt.h"
#include "aia/core/io.h"
#include "aia/core/thread_pool.h"
#include "aia/runtime/episode.h"
#include "aia/runtime/instance.h"
#include "aia/runtime/mission.h"
#include "aia/runtime/observers.h"
#include "aia/runtime/outputs.h"
#include "aia/scenario/yaml.h"

namespace aia {
namespace {

// runs.csv's header (EvalRow::Columns).
const std::string& RunsHeader() {
  static const std::string header = CsvHeader<EvalRow>();
  return header;
}
// Headers of runs.csv written by older aia versions, and what they lack:
// such rows run again.
struct OlderHeader {
  const char* header;
  const char* lacks;
};
constexpr OlderHeader kOlderHeaders[] = {
    {"size,seed,policy,success,flowtime,fstar,bound,wall_s",
     "no reversal columns"},
    {"size,seed,policy,success,flowtime,fstar,bound,reversal_share,"
     "longest_reversal_run,wall_s",
     "no mission_seconds, stalls, timeouts"},
};

// Horizon and denominator of an instance: 3 F* steps, with F* = 0 (targets
// all localized at the start) counted as 1 so that the ratio is defined.
int Horizon(int fstar) { return 3 * std::max(fstar, 1); }

double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
      .count();
}

// The policy keys of the registry's declarations: "policy.p_v" -> "p_v".
std::set<std::string> DeclaredParams(const PolicyRegistry& registry,
                                     const std::string& policy) {
  std::set<std::string> out;
  for (const PolicyInfo& info : registry.Describe())
    if (info.name == policy)
      for (const FieldDoc& d : info.params) out.insert(d.key.substr(7));
  return out;
}

// Where a policy line names a learned policy's model file.
constexpr const char* kModelMark = "; model ";

// DIR/effective.yaml: the instances' scenario and each policy's parameters.
// Policy lines read "#   NAME: {...}", and for a learned policy
// "#   NAME: {...}; model PATH sha256 HEX".
std::string EffectiveText(const EvalSetup& setup, const EvalInstance& first) {
  std::string text =
      "# aia eval: the scenario of every instance, overrides applied. Per\n"
      "# instance, robots.count and targets.count are its size and seed its\n"
      "# seed (--sizes, --seeds, --seed-base); the expert gives F*, and each\n"
      "# policy runs with these parameters:\n";
  text += "#   expert (F*): " + ShowNode(setup.expert->Params(), 100000) + "\n";
  for (const auto& p : setup.policies) {
    text += "#   " + p->name() + ": " + ShowNode(p->Params(), 100000);
    // A learned policy's model by path and content: rows made with a
    // retrained model are not resumed into.
    if (const FileIdentity* model = p->model_file())
      text += kModelMark + model->path + " sha256 " + model->sha256;
    text += "\n";
  }
  // The scenario of a 1x1 world at seed 0, as ever (an older folder's text
  // is compared with it), or of the first instance where overrides fit only
  // the sizes given (a robots.start of two robots).
  Scenario s;
  try {
    s = GeneratedWith(1, 1, 0, setup.overrides);
  } catch (const InputError&) {
    s = InstanceScenario(first, setup);
  }
  s.policy.name = "expert";
  s.policy.params = setup.expert->Params();
  return text + EffectiveYaml(s, "");
}

// The text an exception prints with.
std::string Message(std::exception_ptr failure) {
  try {
    std::rethrow_exception(failure);
  } catch (const InputError& e) {
    return e.Format();
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "an unknown failure";
  }
}

// A policy line of effective.yaml, "#   NAME: PARAMS" (NAME without ':'),
// split; false for any other line.
bool PolicyLine(const std::string& line, std::string* name,
                std::string* params) {
  const std::size_t colon = line.find(':', 4);
  if (line.rfind("#   ", 0) != 0 || colon == std::string::npos || colon <= 4 ||
      colon + 1 >= line.size() || line[colon + 1] != ' ' ||
      line.find('\r', colon) != std::string::npos)
    return false;
  *name = line.substr(4, colon - 4);
  *params = line.substr(colon + 2);
  return true;
}

// Why an existing DIR/effective.yaml does not fit this run, or "".
std::string Mismatch(const std::string& old_text, const std::string& new_text) {
  const auto split = [](const std::string& text) {
    std::map<std::string, std::string> policies;
    std::string body;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
      std::string name, params;
      if (PolicyLine(line, &name, &params)) {
        policies[name] = params;
      } else if (line.rfind("#", 0) != 0) {
        body += line + "\n";
      }
    }
    return std::make_pair(body, policies);
  };
  // Compared as YAML documents: the same scenario written another way (key
  // order, quoting style of a number aside, indentation) is the same.
  const auto same = [](const std::string& a, const std::string& b) {
    if (a == b) return true;
    try {
      return SameValue(ParseYaml(a, "effective.yaml"),
                       ParseYaml(b, "effective.yaml"));
    } catch (const InputError&) {
      return false;  // not YAML: not the same
    }
  };
  const auto [old_body, old_policies] = split(old_text);
  const auto [new_body, new_policies] = split(new_text);
  if (!same(old_body, new_body)) return "the scenario differs (--set)";
  for (const auto& [name, params] : new_policies) {
    const auto it = old_policies.find(name);
    if (it == old_policies.end() || it->second == params) continue;
    const auto cut = [](const std::string& line) {
      const std::size_t at = line.find(kModelMark);
      return std::make_pair(line.substr(0, at),
                            at == std::string::npos ? "" : line.substr(at));
    };
    const auto [old_params, old_model] = cut(it->second);
    const auto [new_params, new_model] = cut(params);
    if (!same(old_params, new_params)) return name + "'s parameters differ";
    if (old_model == new_model) continue;
    return name + "'s model file differs: " +
           (old_model.empty()
                ? std::string("the folder does not record which was used")
                : "another file, or the same one retrained (its SHA-256 "
                  "changed)");
  }
  return "";
}

// `new_text` with the policy lines of `old_text` whose policies it does not
// list, after its own: the rows of those policies stay in the folder.
std::string WithOldPolicyLines(const std::string& old_text,
                               const std::string& new_text) {
  const auto policy_lines = [](const std::string& text) {
    std::vector<std::pair<std::string, std::string>> lines;
    std::istringstream in(text);
    std::string line, name, params;
    while (std::getline(in, line))
      if (PolicyLine(line, &name, &params)) lines.emplace_back(name, line);
    return lines;
  };
  const auto mine = policy_lines(new_text);
  std::string extra;
  for (const auto& [name, line] : policy_lines(old_text)) {
    bool listed = false;
    for (const auto& m : mine) listed = listed || m.first == name;
    if (!listed) extra += line + "\n";
  }
  if (extra.empty() || mine.empty()) return new_text;
  const std::string& last = mine.back().second;
  const std::size_t at = new_text.find(last + "\n") + last.size() + 1;
  return new_text.substr(0, at) + extra + new_text.substr(at);
}

}  // namespace

std::vector<EvalInstance> EnumerateInstances(const std::vector<TeamSize>& sizes,
                                             int seeds,
                                             std::uint64_t seed_base) {
  const std::string why =
      SeedRangeProblem(seed_base, seeds, "--seeds", "--seed-base");
  if (!why.empty()) throw InputError("command line", 0, "--seed-base", why);
  std::vector<EvalInstance> out;
  for (const TeamSize& size : sizes)
    for (int s = 0; s < seeds; ++s)
      out.push_back({size.ToText(), size.robots, size.targets,
                     seed_base + static_cast<std::uint64_t>(s)});
  return out;
}

EvalSetup MakeEvalSetup(const std::vector<std::string>& policies,
                        const std::vector<std::string>& sets,
                        const PolicyRegistry& registry,
                        const std::vector<EvalInstance>& instances) {
  EvalSetup setup;
  std::vector<Override> policy_sets;
  for (const std::string& text : sets) {
    const Override o = ParseSetFlag(text);
    const std::string key = "--set " + o.path;
    if (o.path == "seed" || o.path == "robots.count" ||
        o.path == "targets.count") {
      throw InputError("command line", 0, key,
                       "is set by each instance (--sizes, --seeds, "
                       "--seed-base), not by --set");
    }
    if (o.path == "policy.name")
      throw InputError("command line", 0, key,
                       "the evaluated policies are given by --policies");
    if (o.path.rfind("policy.", 0) == 0 && o.path != "policy.model" &&
        o.path != "policy.model_sha256") {
      policy_sets.push_back(o);
    } else {
      setup.overrides.push_back(o);
    }
  }
  // Checked now, once per size, rather than on every instance: the scenario
  // and the world of its first seed (the other seeds only draw another
  // world, which can still fail: RunInstance names the flag too).
  std::vector<EvalInstance> checked;
  for (const EvalInstance& inst : instances) {
    bool seen = false;
    for (const EvalInstance& c : checked) seen = seen || c.size == inst.size;
    if (!seen) checked.push_back(inst);
  }
  Scenario base;
  for (const EvalInstance& inst : checked) {
    const Scenario s = InstanceScenario(inst, setup);
    try {
      BuildInstance(s);
    } catch (const InputError& e) {
      NameTheFlag(e, InstanceSpec(inst, setup));
    }
    if (&inst == &checked.front()) base = s;
  }
  if (checked.empty()) base = InstanceScenario({"1x1", 1, 1, 0}, setup);
  std::set<std::string> used;
  const auto resolve = [&](const std::string& name) {
    const std::set<std::string> declared = DeclaredParams(registry, name);
    std::vector<Override> own;
    for (const Override& o : policy_sets) {
      if (declared.count(o.path.substr(7))) {
        own.push_back(o);
        used.insert(o.path);
      }
    }
    Scenario s = base;
    s.policy.name = name;
    return registry.Resolve(WithOverrides(s, own));
  };
  setup.expert = resolve("expert");
  for (const std::string& p : policies) {
    if (!registry.Has(p))
      throw InputError("command line", 0, "--policies",
                       registry.UnknownPolicy(p));
    setup.policies.push_back(resolve(p));
  }
  for (const Override& o : policy_sets) {
    if (!used.count(o.path)) {
      std::string names = "expert";
      for (const std::string& p : policies) names += ", " + p;
      throw InputError("command line", 0, "--set " + o.path,
                       "no policy of this evaluation (" + names +
                           ") has the parameter `" + o.path.substr(7) +
                           "` (aia policies lists them)");
    }
  }
  return setup;
}

GeneratedSpec InstanceSpec(const EvalInstance& instance,
                           const EvalSetup& setup) {
  GeneratedSpec spec;
  spec.size = instance.size;
  spec.robots = instance.robots;
  spec.targets = instance.targets;
  spec.seed = instance.seed;
  spec.overrides = setup.overrides;
  return spec;
}

Scenario InstanceScenario(const EvalInstance& instance,
                          const EvalSetup& setup) {
  return ReadGenerated(InstanceSpec(instance, setup));
}

std::vector<EvalRow> RunInstance(const EvalInstance& inst,
                                 const EvalSetup& setup,
                                 const std::vector<std::string>& policies) {
  std::shared_ptr<const Instance> instance;
  try {
    instance = BuildInstance(InstanceScenario(inst, setup));
  } catch (const InputError& e) {
    NameTheFlag(e, InstanceSpec(inst, setup));
  }
  const SamplingPlan plan =
      PlanFromStart(instance, *ParamsOf<ExpertParams>(*setup.expert));
  const int fstar = plan.found ? plan.depth : -1;
  std::vector<EvalRow> rows;
  for (const auto& spec : setup.policies) {
    if (!policies.empty() && std::find(policies.begin(), policies.end(),
                                       spec->name()) == policies.end())
      continue;
    EvalRow row;
    row.size = inst.size;
    row.seed = inst.seed;
    row.policy = spec->name();
    row.fstar = fstar;
    row.bound = plan.bound;
    if (fstar >= 0) {
      const auto t0 = std::chrono::steady_clock::now();
      MissionConfig mission = instance->scenario.mission;
      mission.max_steps = Horizon(fstar);
      Episode episode(instance, spec->Create(), mission);
      MoveObserver moves;
      episode.AddObserver(&moves);
      episode.Run();
      if (episode.interrupted()) throw RunInterrupted();
      row.success = episode.success();
      row.flowtime = episode.flowtime();
      row.reversal_share =
          moves.moves() > 0
              ? static_cast<double>(moves.reversals()) / moves.moves()
              : 0.0;
      row.longest_reversal_run = moves.longest_reversal_run();
      row.mission_seconds = episode.mission_seconds();
      for (const long c : episode.sim().robot_stalls()) row.stalls += c;
      for (const long c : episode.sim().robot_timeouts()) row.timeouts += c;
      row.wall_s = SecondsSince(t0);
    }
    rows.push_back(row);
  }
  return rows;
}

// A row of runs.csv is some 100 bytes; a longer line is not one.
constexpr std::size_t kMaxRunsLine = 64 * 1024;

// Why a parsed row cannot be a run's result, or "".
std::string Impossible(const EvalRow& r) {
  std::string why;
  if (!TeamSize::FromText(r.size, &why)) return "size '" + r.size + "'";
  const bool name_ok =
      !r.policy.empty() && r.policy.size() <= 64 &&
      std::all_of(r.policy.begin(), r.policy.end(), [](char c) {
        return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
               (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
      });
  if (!name_ok) return "policy '" + r.policy + "'";
  if (r.fstar < -1) return "fstar " + std::to_string(r.fstar);
  if (r.bound < -1) return "bound " + std::to_string(r.bound);
  if (!std::isfinite(r.wall_s) || r.wall_s < 0) return "wall_s";
  if (!(r.reversal_share >= 0.0 && r.reversal_share <= 1.0))
    return "reversal_share";
  if (r.longest_reversal_run < 0) return "longest_reversal_run";
  if (!std::isfinite(r.mission_seconds) || r.mission_seconds < 0)
    return "mission_seconds";
  if (r.stalls < 0) return "stalls";
  if (r.timeouts < 0) return "timeouts";
  if (r.flowtime < -1) return "flowtime " + std::to_string(r.flowtime);
  if (r.success && r.flowtime < 0) return "a success without a flowtime";
  if (r.success && r.fstar >= 0 && r.flowtime > Horizon(r.fstar))
    return "flowtime " + std::to_string(r.flowtime) + " beyond the horizon " +
           std::to_string(Horizon(r.fstar));
  return "";
}

std::vector<EvalRow> ReadRuns(const std::string& path,
                              std::vector<std::string>* problems) {
  std::vector<EvalRow> rows;
  std::vector<int> lines;
  // Line by line, each at most kMaxRunsLine bytes: a runs.csv cut by a crash
  // may end in gigabytes of NULs (a 3 GB tail took 12 GB of memory).
  std::optional<LineReader> in;
  std::string line;
  int number = 0;
  const auto next = [&]() {
    try {
      if (!in) in.emplace(path, kMaxRunsLine);
      return in->Next(&line);
    } catch (const LineTooLong& e) {
      throw InputError("command line", 0, "--out",
                       "cannot resume from '" + path + "': " + e.what() +
                           ", which no row of aia eval is (a file cut by a "
                           "crash may end in NULs); remove that line and "
                           "what follows, or use another folder");
    } catch (const std::runtime_error& e) {
      throw InputError("command line", 0, "--out",
                       "cannot resume from '" + path + "': " + e.what());
    }
  };
  const auto report = [&](int at, const std::string& why) {
    if (problems)
      problems->push_back("line " + std::to_string(at) + ": " + why);
  };
  while (next()) {
    ++number;
    EvalRow r;
    if (line == RunsHeader() || line.empty()) continue;
    if (number == 1) {
      const OlderHeader* older = nullptr;
      for (const OlderHeader& h : kOlderHeaders)
        if (line == h.header) older = &h;
      if (older) {
        report(number, std::string("the header of an older aia (") +
                           older->lacks + ")");
        continue;
      }
    }
    if (!ParseCsvLine(line, &r)) {
      report(number, "not a row");
      continue;
    }
    if (const std::string why = Impossible(r); !why.empty()) {
      report(number, "impossible " + why);
      continue;
    }
    rows.push_back(r);
    lines.push_back(number);
  }
  // A run found twice: which copy is right is unknown, so neither is kept.
  std::map<std::tuple<std::string, std::uint64_t, std::string>, int> count;
  for (const EvalRow& r : rows) ++count[{r.size, r.seed, r.policy}];
  std::vector<EvalRow> kept;
  for (size_t i = 0; i < rows.size(); ++i) {
    const EvalRow& r = rows[i];
    if (count[{r.size, r.seed, r.policy}] > 1) {
      report(lines[i], "duplicate run " + r.size + " seed " +
                           std::to_string(r.seed) + " " + r.policy);
    } else {
      kept.push_back(r);
    }
  }
  return kept;
}

void EvalOptions::Validate(const FieldChecker& c) const {
  if (sizes.empty()) c.Fail(sizes, "give at least one size");
  for (std::size_t i = 0; i < sizes.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (sizes[i] == sizes[j])
        c.Fail(sizes, "'" + sizes[i].ToText() + "' is listed twice");
  for (std::size_t i = 0; i < policies.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (policies[i] == policies[j])
        c.Fail(policies, "'" + policies[i] + "' is listed twice");
  const std::string why =
      SeedRangeProblem(seed_base, seeds, "--seeds", "--seed-base");
  if (!why.empty()) c.Fail(seed_base, why);
}

std::string SummaryCsv(const std::vector<EvalRow>& rows,
                       const std::vector<std::string>& sizes,
                       const std::vector<std::string>& policies) {
  std::string out = CsvHeader<SummaryRow>() + "\n";
  for (const auto& size : sizes) {
    for (const auto& policy : policies) {
      int n = 0, ok = 0, no_plan = 0, longest = 0;
      double inc = 0.0, flow = 0.0, fstar = 0.0, gap = 0.0, reversals = 0.0;
      double seconds = 0.0, stalls = 0.0, timeouts = 0.0;
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
        gap += static_cast<double>(r.fstar) / std::max(r.bound, 1);
        reversals += r.reversal_share;
        longest = std::max(longest, r.longest_reversal_run);
        seconds += r.mission_seconds;
        stalls += static_cast<double>(r.stalls);
        timeouts += static_cast<double>(r.timeouts);
      }
      SummaryRow row;
      row.size = size;
      row.policy = policy;
      row.instances = n;
      row.no_expert_plan = no_plan;
      if (n > 0) {
        row.success_rate = static_cast<double>(ok) / n;
        row.flowtime_increase = inc / n;
        row.mean_flowtime = flow / n;
        row.mean_fstar = fstar / n;
        row.mean_fstar_over_bound = gap / n;
        row.reversal_share = reversals / n;
        row.longest_reversal_run = longest;
        row.mission_seconds = seconds / n;
        row.stalls = stalls / n;
        row.timeouts = timeouts / n;
      }
      out += CsvLine(row);
    }
  }
  return out;
}

namespace {

std::vector<std::string> SizeLabels(const std::vector<TeamSize>& sizes) {
  std::vector<std::string> labels;
  for (const TeamSize& s : sizes) labels.push_back(s.ToText());
  return labels;
}

// The flags that need no scenario (their declarations: `--flag: what`) and
// the output folder.
void CheckEvalFlags(const EvalOptions& o) {
  EvalOptions flags = o;
  CheckFlags(&flags);
  if (o.out_dir.empty())
    throw InputError("command line", 0, "--out",
                     "an output folder is required");
  // Before any work: a FIFO at runs.csv blocked the resume's open for ever.
  CheckOutputFiles({o.out_dir + "/runs.csv", o.out_dir + "/summary.csv",
                    o.out_dir + "/effective.yaml"},
                   "--out", "written into the output folder");
}

// --policies, or every registered policy but the expert.
std::vector<std::string> PoliciesToRun(const EvalOptions& o,
                                       const PolicyRegistry& registry) {
  std::vector<std::string> policies = o.policies;
  if (policies.empty() && o.extra_policies.empty()) {
    for (const auto& name : registry.Names())
      if (name != "expert") policies.push_back(name);
  }
  return policies;
}

// No file written may be an input (a model, a map image).
void CheckOutputsAreNotInputs(const EvalOptions& o, const EvalSetup& setup,
                              const EvalInstance& first) {
  std::vector<InputFile> inputs =
      MissionInputs(InstanceScenario(first, setup), nullptr);
  for (const auto& p : setup.policies)
    for (const InputFile& f : MissionInputs(Scenario{}, p.get()))
      inputs.push_back(f);
  for (const char* name : {"runs.csv", "summary.csv", "effective.yaml"})
    CheckNotAnInput(o.out_dir + "/" + name, "--out", inputs,
                    "written into the output folder");
}

// The effective.yaml aia writes is a few KiB.
constexpr std::uintmax_t kMaxEffectiveBytes = 16u << 20;

// Rank 0's resume: locks the output folder, refuses one that holds results
// of another configuration, keeps the rows already there (a row cut short
// by an interruption, garbled, impossible or duplicated is reported, dropped
// and run again), rewrites runs.csv cleanly and writes effective.yaml.
std::vector<EvalRow> ResumeFolder(const std::string& out_dir,
                                  const std::string& effective) {
  const std::string effective_path = out_dir + "/effective.yaml";
  const std::string runs_path = out_dir + "/runs.csv";
  MakeOutputDir(out_dir, "--out", /*lock=*/true);
  std::string merged = effective;
  std::error_code ec;
  if (std::filesystem::exists(effective_path, ec)) {
    // Read without blocking (a FIFO is refused) and within a bound: the
    // file aia writes is a few KiB.
    std::string text;
    try {
      text = ReadFile(effective_path, kMaxEffectiveBytes);
    } catch (const std::runtime_error& e) {
      throw InputError(
          "command line", 0, "--out",
          "cannot resume from '" + effective_path + "': " + e.what());
    }
    const std::string why = Mismatch(text, effective);
    if (!why.empty())
      throw InputError("command line", 0, "--out",
                       out_dir + " holds results of another configuration (" +
                           why + "; see its effective.yaml): use a new folder");
    merged = WithOldPolicyLines(text, effective);
  }
  std::vector<std::string> problems;
  std::vector<EvalRow> rows = ReadRuns(runs_path, &problems);
  if (!problems.empty()) {
    std::string shown;
    for (size_t i = 0; i < problems.size() && i < 5; ++i)
      shown += (i ? "; " : "") + problems[i];
    if (problems.size() > 5)
      shown += "; ... (" + std::to_string(problems.size() - 5) + " more)";
    std::fprintf(stderr,
                 "aia eval: %s: dropped %zu rows that will run again: %s\n",
                 runs_path.c_str(), problems.size(), shown.c_str());
  }
  std::string text = RunsHeader() + "\n";
  for (const auto& r : rows) text += CsvLine(r);
  WriteFileAtomic(runs_path, text);
  WriteFileAtomic(effective_path, merged);
  return rows;
}

// One instance's policies still to run.
struct Work {
  const EvalInstance* instance;
  std::vector<std::string> todo;
};

// The runs not in `done`, and this rank's round-robin share of them (the
// same split on every rank); *total_runs counts every rank's runs.
std::vector<Work> WorkLeft(const std::vector<EvalInstance>& instances,
                           const std::vector<std::string>& policies,
                           const std::vector<EvalRow>& done_rows,
                           const Ranks& ranks, int* total_runs) {
  std::set<std::tuple<std::string, std::uint64_t, std::string>> done;
  for (const auto& r : done_rows) done.insert({r.size, r.seed, r.policy});
  std::vector<Work> work;
  *total_runs = 0;
  for (const EvalInstance& inst : instances) {
    Work w{&inst, {}};
    for (const auto& p : policies)
      if (!done.count({inst.size, inst.seed, p})) w.todo.push_back(p);
    *total_runs += static_cast<int>(w.todo.size());
    if (!w.todo.empty()) work.push_back(std::move(w));
  }
  std::vector<Work> mine;
  for (size_t i = 0; i < work.size(); ++i)
    if (static_cast<int>(i % ranks.size()) == ranks.rank())
      mine.push_back(std::move(work[i]));
  return mine;
}

// Where finished rows go. On rank 0 each is appended to runs.csv as it
// finishes (its own, and those the other ranks send), so that an
// interrupted eval loses only the runs in flight; the other ranks send
// theirs to rank 0. Record() and WriteResults() are called under mutex().
class RowSink {
 public:
  RowSink(const EvalOptions& o, const std::vector<std::string>& policies,
          std::vector<EvalRow> rows, int total_runs, bool root, Ranks* ranks)
      : options_(o),
        policies_(policies),
        runs_path_(o.out_dir + "/runs.csv"),
        rows_(std::move(rows)),
        total_runs_(total_runs),
        root_(root),
        ranks_(ranks),
        progress_(o.progress && root) {
    if (!root_) return;
    // runs.csv was just written as a regular file; O_NONBLOCK keeps even a
    // FIFO swapped in since from blocking the open.
    fd_ = ::open(runs_path_.c_str(), O_WRONLY | O_APPEND | O_NONBLOCK);
    struct stat st;
    if (fd_ >= 0 && (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode))) {
      ::close(fd_);
      fd_ = -1;
      errno = EINVAL;
    }
    if (fd_ < 0)
      throw std::runtime_error("cannot write '" + runs_path_ +
                               "': " + std::strerror(errno));
    ::fcntl(fd_, F_SETFL, ::fcntl(fd_, F_GETFL) & ~O_NONBLOCK);
  }
  ~RowSink() {
    if (fd_ >= 0) ::close(fd_);
  }
  RowSink(const RowSink&) = delete;
  RowSink& operator=(const RowSink&) = delete;

  std::mutex& mutex() { return mu_; }
  const std::string& runs_path() const { return runs_path_; }
  std::size_t rows() const { return rows_.size(); }

  void Record(const EvalRow& row) {
    const std::string line = CsvLine(row);
    if (!root_) {
      ranks_->SendLine(line);
      return;
    }
    if (::write(fd_, line.data(), line.size()) !=
        static_cast<ssize_t>(line.size()))
      throw std::runtime_error("cannot write '" + runs_path_ + "': " +
                               std::strerror(errno != 0 ? errno : ENOSPC));
    // Kept as the file holds it (its columns rounded), so that summary.csv
    // is the same whether the rows were run now or read by a resume.
    EvalRow written;
    AIA_CHECK(ParseCsvLine(line.substr(0, line.size() - 1), &written));
    rows_.push_back(written);
    ++finished_;
    char buf[200];
    std::snprintf(buf, sizeof(buf),
                  "[aia eval] %d/%d runs  (last: %s seed %llu)", finished_,
                  total_runs_, row.size.c_str(),
                  static_cast<unsigned long long>(row.seed));
    progress_.Update(buf);
  }

  // The appended rows on disk, and the progress line ended.
  void Flush() {
    progress_.Finish();
    if (fd_ >= 0) ::fsync(fd_);
  }

  // runs.csv rewritten in canonical order (so that the files do not depend
  // on the thread count) and summary.csv of this eval's seeds; returns the
  // summary.
  std::string WriteResults() {
    std::map<std::string, size_t> size_rank, policy_rank;
    const std::vector<std::string> sizes = SizeLabels(options_.sizes);
    for (size_t i = 0; i < sizes.size(); ++i) size_rank.emplace(sizes[i], i);
    for (size_t i = 0; i < policies_.size(); ++i)
      policy_rank.emplace(policies_[i], i);
    const auto rank = [](const std::map<std::string, size_t>& m,
                         const std::string& k) {
      const auto it = m.find(k);
      return it == m.end() ? m.size() : it->second;
    };
    std::stable_sort(
        rows_.begin(), rows_.end(), [&](const EvalRow& a, const EvalRow& b) {
          return std::make_tuple(rank(size_rank, a.size), a.size, a.seed,
                                 rank(policy_rank, a.policy), a.policy) <
                 std::make_tuple(rank(size_rank, b.size), b.size, b.seed,
                                 rank(policy_rank, b.policy), b.policy);
        });
    std::string text = RunsHeader() + "\n";
    for (const auto& r : rows_) text += CsvLine(r);
    WriteFileAtomic(runs_path_, text);
    // summary.csv covers every row of runs.csv: this eval's sizes and
    // policies first, then those of other rows in the folder (an earlier
    // eval's, a Python policy's), so that they share one table and the
    // summary never depends on which command wrote it last (issue 37: a
    // resume of some sizes summarized another policy's rows of those sizes
    // and dropped the other sizes).
    std::vector<std::string> all_sizes = sizes, policies = policies_;
    for (const auto& r : rows_) {
      if (std::find(all_sizes.begin(), all_sizes.end(), r.size) ==
          all_sizes.end())
        all_sizes.push_back(r.size);
      if (std::find(policies.begin(), policies.end(), r.policy) ==
          policies.end())
        policies.push_back(r.policy);
    }
    const std::string summary = SummaryCsv(rows_, all_sizes, policies);
    WriteFileAtomic(options_.out_dir + "/summary.csv", summary);
    coverage_ = Coverage(all_sizes, policies);
    return summary;
  }

  // What summary.csv covers, for the last line of the command.
  const std::string& coverage() const { return coverage_; }

 private:
  const EvalOptions& options_;
  const std::vector<std::string>& policies_;
  std::string runs_path_;
  std::vector<EvalRow> rows_;
  int total_runs_;
  int finished_ = 0;
  bool root_;
  Ranks* ranks_;
  ProgressLine progress_;
  int fd_ = -1;
  std::mutex mu_;
  std::string coverage_;

  // "all 24 rows of runs.csv: sizes 2x2, 3x3; seeds 0 to 5; policies
  // greedy, random".
  std::string Coverage(const std::vector<std::string>& sizes,
                       const std::vector<std::string>& policies) const {
    const auto join = [](const std::vector<std::string>& v) {
      std::string out;
      for (const std::string& x : v) {
        if (out.size() > 200) return out + ", ...";
        out += (out.empty() ? "" : ", ") + x;
      }
      return out;
    };
    std::set<std::uint64_t> seeds;
    for (const EvalRow& r : rows_) seeds.insert(r.seed);
    return "all " + std::to_string(rows_.size()) + " rows of runs.csv: sizes " +
           join(sizes) +
           (seeds.empty() ? std::string()
                          : "; " + std::to_string(seeds.size()) +
                                (seeds.size() == 1 ? " seed, " : " seeds, ") +
                                std::to_string(*seeds.begin()) + " to " +
                                std::to_string(*seeds.rbegin())) +
           "; policies " + join(policies);
  }
};

// The threads to run on: --threads, or all cores shared among the ranks on
// this machine; never more than there is work.
int WorkerThreads(int requested, std::size_t work) {
  int threads = requested;
  if (threads == 0) {
    threads = static_cast<int>(std::thread::hardware_concurrency());
    if (const char* local = std::getenv("OMPI_COMM_WORLD_LOCAL_SIZE"))
      threads /= std::max(1, std::atoi(local));
  }
  return std::max(
      1, std::min<int>(threads, static_cast<int>(std::max<size_t>(work, 1))));
}

// The work queue: `threads` threads of a pool take instances in turn and
// record their rows; the first failure of a run (bad input found in it, say:
// a generated world that cannot be built) stops the handing out and is kept
// as it is. Start() returns at once; Join() waits.
class WorkQueue {
 public:
  WorkQueue(const std::vector<Work>& work, const EvalSetup& setup,
            RowSink* sink, int threads)
      : work_(work), setup_(setup), sink_(sink), pool_(threads) {}

  void Start() {
    pool_.Start(static_cast<int>(work_.size()), [this](int w, int) {
      if (Interrupted()) {
        pool_.Cancel();
        return;
      }
      std::vector<EvalRow> result;
      try {
        result = RunInstance(*work_[w].instance, setup_, work_[w].todo);
      } catch (const RunInterrupted&) {
        pool_.Cancel();  // no row of a run cut short
        return;
      }
      std::lock_guard<std::mutex> lock(sink_->mutex());
      for (const EvalRow& row : result) sink_->Record(row);
    });
  }
  // Whether every run has ended; in one process, Ctrl-C ends the wait
  // early.
  bool WaitUnlessInterrupted(bool interruptible) {
    for (;;) {
      if (pool_.WaitFor(std::chrono::milliseconds(20))) return true;
      if (interruptible && Interrupted()) return false;
    }
  }
  // Waits for the runs; the first failure, or nullptr.
  std::exception_ptr Join() {
    try {
      pool_.Wait();
    } catch (...) {
      return std::current_exception();
    }
    return nullptr;
  }

 private:
  const std::vector<Work>& work_;
  const EvalSetup& setup_;
  RowSink* sink_;
  ThreadPool pool_;
};

// Rank 0 under mpirun: the rows the other ranks send, recorded as they
// come; the first problem is kept in *error.
std::thread ReceiveRemoteRows(Ranks* ranks, RowSink* sink, std::string* error,
                              std::string* remote_error) {
  return std::thread([ranks, sink, error, remote_error]() {
    *remote_error = ranks->ReceiveAll([&](const std::string& line) {
      EvalRow row;
      std::string text = line;
      if (!text.empty() && text.back() == '\n') text.pop_back();
      std::lock_guard<std::mutex> lock(sink->mutex());
      if (!ParseCsvLine(text, &row)) {
        if (error->empty()) *error = "a rank sent a bad row";
        return;
      }
      try {
        sink->Record(row);
      } catch (const std::exception& e) {
        if (error->empty()) *error = e.what();
      }
    });
  });
}

}  // namespace

int RunEval(const EvalOptions& o) {
  CheckEvalFlags(o);
  const PolicyRegistry registry = AllPolicies();
  // One process: Ctrl-C writes the rows done (below). Under mpirun the
  // launcher owns the signals.
  Ranks& ranks = Ranks::Get();
  if (!ranks.distributed()) InstallInterruptHandler();
  std::vector<std::string> policies = PoliciesToRun(o, registry);
  const std::vector<EvalInstance> instances =
      EnumerateInstances(o.sizes, o.seeds, o.seed_base);
  EvalSetup setup = MakeEvalSetup(policies, o.sets, registry, instances);
  for (const auto& extra : o.extra_policies) {
    if (registry.Has(extra->name()) ||
        std::find(policies.begin(), policies.end(), extra->name()) !=
            policies.end())
      throw InputError("command line", 0, "name",
                       "'" + extra->name() +
                           "' is a registered policy's name or listed twice; "
                           "give the policy another name");
    setup.policies.push_back(extra);
    policies.push_back(extra->name());
  }
  CheckOutputsAreNotInputs(o, setup, instances.front());

  // Rank 0 alone checks and rewrites the folder; then every rank reads the
  // rows already done and takes its share of the rest.
  const bool root = ranks.rank() == 0;
  const std::string effective_path = o.out_dir + "/effective.yaml";
  std::vector<EvalRow> rows;
  if (root) {
    try {
      rows = ResumeFolder(o.out_dir, EffectiveText(setup, instances.front()));
    } catch (...) {
      ranks.AgreeFromRoot(false);  // the other ranks stop quietly
      throw;
    }
  }
  if (!ranks.AgreeFromRoot(true)) return 2;
  if (!root) rows = ReadRuns(o.out_dir + "/runs.csv");
  int total_runs = 0;
  const std::vector<Work> work =
      WorkLeft(instances, policies, rows, ranks, &total_runs);
  if (root) {
    std::printf(
        "aia eval: %zu sizes x %d seeds x %zu policies; %zu rows already "
        "done, %d to run%s\n",
        o.sizes.size(), o.seeds, policies.size(), rows.size(), total_runs,
        ranks.distributed()
            ? (" on " + std::to_string(ranks.size()) + " MPI ranks").c_str()
            : "");
    std::fflush(stdout);
  }

  RowSink sink(o, policies, std::move(rows), total_runs, root, &ranks);
  std::string first_error, remote_error;
  std::thread receiver;
  if (root && ranks.distributed())
    receiver = ReceiveRemoteRows(&ranks, &sink, &first_error, &remote_error);
  WorkQueue queue(work, setup, &sink, WorkerThreads(o.threads, work.size()));
  queue.Start();
  // Ctrl-C (one process): the rows finished so far are written, with the
  // summary of what is done, and the runs in flight are abandoned.
  if (!queue.WaitUnlessInterrupted(root && !ranks.distributed()) &&
      o.exit_on_interrupt) {
    std::lock_guard<std::mutex> lock(sink.mutex());  // no row is appended
    sink.Flush();
    sink.WriteResults();
    std::fprintf(stderr,
                 "aia eval: interrupted; %zu rows written to %s (summary.csv "
                 "covers %s); run the same command to go on\n",
                 sink.rows(), sink.runs_path().c_str(),
                 sink.coverage().c_str());
    std::fflush(stderr);
    std::_Exit(kInterruptedExitCode);
  }
  const std::exception_ptr failure = queue.Join();
  if (!root) {
    ranks.SendDone(failure ? Message(failure) : first_error);
    return 0;  // rank 0 reports
  }
  if (receiver.joinable()) receiver.join();
  sink.Flush();
  if (failure) std::rethrow_exception(failure);
  if (first_error.empty()) first_error = remote_error;
  if (!first_error.empty()) throw std::runtime_error(first_error);

  const std::string summary = sink.WriteResults();
  if (Interrupted()) {
    std::fprintf(stderr,
                 "aia eval: interrupted; %zu rows written to %s; run the same "
                 "command to go on\n",
                 sink.rows(), sink.runs_path().c_str());
    return kInterruptedExitCode;
  }
  std::printf("%s", summary.c_str());
  std::printf("wrote %s, %s/summary.csv (of %s) and %s\n",
              sink.runs_path().c_str(), o.out_dir.c_str(),
              sink.coverage().c_str(), effective_path.c_str());
  return 0;
}

}  // namespace aia
