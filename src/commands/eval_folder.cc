#include "aia/commands/eval_folder.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <tuple>

#include "aia/commands/ranks.h"
#include "aia/core/check.h"
#include "aia/core/error.h"
#include "aia/core/io.h"
#include "aia/runtime/outputs.h"
#include "aia/scenario/loader.h"
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
  if (r.success && r.fstar >= 0 && r.flowtime > EvalHorizon(r.fstar))
    return "flowtime " + std::to_string(r.flowtime) + " beyond the horizon " +
           std::to_string(EvalHorizon(r.fstar));
  return "";
}

std::vector<std::string> SizeLabels(const std::vector<TeamSize>& sizes) {
  std::vector<std::string> labels;
  for (const TeamSize& s : sizes) labels.push_back(s.ToText());
  return labels;
}

// The effective.yaml aia writes is a few KiB.
constexpr std::uintmax_t kMaxEffectiveBytes = 16u << 20;

// effective.yaml's key of the evaluated policies.
constexpr const char* kPolicies = "policies";
// The keys of a policy's entry that name its model file rather than
// parameters (PolicyConfig's model and model_sha256).
constexpr const char* kModelKeys[] = {"model", "model_sha256"};

// An older effective.yaml's policy lines: "#   NAME: PARAMS", PARAMS a flow
// mapping, for a learned policy followed by "; model PATH sha256 HEX". The
// line "#   expert (F*): ..." repeats the scenario's policy section.
constexpr const char* kOlderModelMark = "; model ";
constexpr const char* kOlderExpertLine = "expert (F*)";

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

// The policies of an older effective.yaml's comment lines, as EvalConfig
// writes them (before the round trip through YAML text).
ConfigNode OlderPolicies(const std::string& text, const std::string& file) {
  ConfigNode policies = ConfigNode::Map();
  std::istringstream in(text);
  std::string line, name, params;
  for (int number = 1; std::getline(in, line); ++number) {
    if (!PolicyLine(line, &name, &params) || name == kOlderExpertLine) continue;
    const std::size_t at = params.find(kOlderModelMark);
    ConfigNode entry;
    try {
      entry = ParseYaml(params.substr(0, at), file);
    } catch (const InputError& e) {
      throw InputError(
          file, number, ChildKey(kPolicies, name),
          "the parameters in this comment line are not YAML: " + e.message());
    }
    if (entry.IsNull()) entry = ConfigNode::Map();
    if (!entry.IsMap())
      throw InputError(file, number, ChildKey(kPolicies, name),
                       "the parameters in this comment line are not a "
                       "mapping: " +
                           ShowNode(entry));
    if (at != std::string::npos) {
      const std::string model =
          params.substr(at + std::strlen(kOlderModelMark));
      const std::size_t sha = model.rfind(" sha256 ");
      entry.Set(kModelKeys[0], ConfigNode::Scalar(model.substr(0, sha)));
      if (sha != std::string::npos)
        entry.Set(kModelKeys[1], ConfigNode::Scalar(model.substr(sha + 8)));
    }
    policies.Set(name, std::move(entry));
  }
  return policies;
}

// A configuration's scenario keys (all but `policies`).
ConfigNode ScenarioPart(const ConfigNode& config) {
  ConfigNode scenario = config;
  scenario.Erase(kPolicies);
  return scenario;
}

// A policy's entry split into its parameters and its model file.
std::pair<ConfigNode, ConfigNode> ParamsAndModel(const ConfigNode& entry) {
  ConfigNode params = entry, model = ConfigNode::Map();
  for (const char* key : kModelKeys) {
    if (const ConfigNode* value = entry.Find(key)) model.Set(key, *value);
    params.Erase(key);
  }
  return {params, model};
}

}  // namespace

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
      throw InputError::Flag(
          "--out", "cannot resume from '" + path + "': " + e.what() +
                       ", which no row of aia eval is (a file cut by a "
                       "crash may end in NULs); remove that line and "
                       "what follows, or use another folder");
    } catch (const std::runtime_error& e) {
      throw InputError::Flag("--out",
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

ConfigNode EvalConfig(const EvalSetup& setup, const EvalInstance& first) {
  ConfigNode policies = ConfigNode::Map();
  for (const auto& p : setup.policies) {
    ConfigNode entry = p->Params();
    if (entry.IsNull()) entry = ConfigNode::Map();
    // A learned policy's model by path and content: rows made with a
    // retrained model are not resumed into.
    if (const FileIdentity* model = p->model_file()) {
      entry.Set(kModelKeys[0], ConfigNode::Scalar(model->path));
      entry.Set(kModelKeys[1], ConfigNode::Scalar(model->sha256));
    }
    policies.Set(p->name(), std::move(entry));
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
  ConfigNode config = ConfigNode::Map();
  config.Set(kPolicies, std::move(policies));
  for (ConfigNode::Entry& e : ScenarioNode(s).entries)
    config.entries.push_back(std::move(e));
  // As the file reads back (its scalars' styles), so that a folder's tree
  // compares with it.
  return ParseYaml(EmitYaml(config), "effective.yaml");
}

std::string EvalConfigText(const ConfigNode& config) {
  return "# aia eval: the configuration of this folder's rows; a resume into\n"
         "# the folder must match it. `policies` holds each evaluated "
         "policy's\n"
         "# parameters (a learned policy's model file by path and SHA-256).\n"
         "# The other keys are the scenario of every instance, overrides\n"
         "# applied: per instance, robots.count and targets.count are its "
         "size\n"
         "# and seed its seed (--sizes, --seeds, --seed-base), and its policy\n"
         "# is the expert that gives F*.\n" +
         EmitYaml(config);
}

ConfigNode ReadEvalConfig(const std::string& text, const std::string& file) {
  ConfigNode config = ParseYaml(text, file);
  if (config.IsNull()) config = ConfigNode::Map();
  if (!config.IsMap())
    throw InputError(file, config.line, "(yaml)",
                     "must be a mapping of scenario keys and `policies`, got " +
                         ShowNode(config));
  if (const ConfigNode* policies = config.Find(kPolicies)) {
    if (!policies->IsMap())
      throw InputError(file, policies->line, kPolicies,
                       "must be a mapping of policy names to their "
                       "parameters, got " +
                           ShowNode(*policies));
    for (const ConfigNode::Entry& e : policies->entries)
      if (!e.value.IsMap())
        throw InputError(file, e.value.line, ChildKey(kPolicies, e.key),
                         "must be a mapping of the policy's parameters, got " +
                             ShowNode(e.value));
    return config;
  }
  // An older aia's folder: the policies in comment lines, brought to the
  // form of this one's (through the same YAML text).
  ConfigNode older = ConfigNode::Map();
  older.Set(kPolicies, OlderPolicies(text, file));
  for (ConfigNode::Entry& e : config.entries)
    older.entries.push_back(std::move(e));
  return ParseYaml(EmitYaml(older), file);
}

std::string ConfigMismatch(const ConfigNode& folder, const ConfigNode& run) {
  if (!SameValue(ScenarioPart(folder), ScenarioPart(run)))
    return "the scenario differs (--set)";
  const ConfigNode* old_policies = folder.Find(kPolicies);
  const ConfigNode* new_policies = run.Find(kPolicies);
  if (!old_policies || !new_policies) return "";
  for (const ConfigNode::Entry& e : new_policies->entries) {
    const ConfigNode* old_entry = old_policies->Find(e.key);
    if (!old_entry) continue;
    const auto [old_params, old_model] = ParamsAndModel(*old_entry);
    const auto [new_params, new_model] = ParamsAndModel(e.value);
    if (!SameValue(old_params, new_params))
      return e.key + "'s parameters differ";
    if (SameValue(old_model, new_model)) continue;
    return e.key + "'s model file differs: " +
           (old_model.entries.empty()
                ? std::string("the folder does not record which was used")
                : "another file, or the same one retrained (its SHA-256 "
                  "changed)");
  }
  return "";
}

ConfigNode WithFolderPolicies(const ConfigNode& folder, const ConfigNode& run) {
  ConfigNode merged = run;
  const ConfigNode* old_policies = folder.Find(kPolicies);
  ConfigNode* policies = merged.Find(kPolicies);
  if (!old_policies || !policies) return merged;
  for (const ConfigNode::Entry& e : old_policies->entries)
    if (!policies->Find(e.key)) policies->entries.push_back(e);
  return merged;
}

std::vector<EvalRow> ResumeFolder(const std::string& out_dir,
                                  const ConfigNode& config) {
  const std::string effective_path = out_dir + "/effective.yaml";
  const std::string runs_path = out_dir + "/runs.csv";
  MakeOutputDir(out_dir, "--out", /*lock=*/true);
  ConfigNode merged = config;
  std::error_code ec;
  const bool checked = std::filesystem::exists(effective_path, ec);
  if (checked) {
    // Read without blocking (a FIFO is refused) and within a bound: the
    // file aia writes is a few KiB.
    std::string text;
    try {
      text = ReadFile(effective_path, kMaxEffectiveBytes);
    } catch (const std::runtime_error& e) {
      throw InputError::Flag(
          "--out", "cannot resume from '" + effective_path + "': " + e.what());
    }
    const ConfigNode folder = ReadEvalConfig(text, effective_path);
    const std::string why = ConfigMismatch(folder, config);
    if (!why.empty())
      throw InputError::Flag(
          "--out", out_dir + " holds results of another configuration (" + why +
                       "; see its effective.yaml): use a new folder");
    merged = WithFolderPolicies(folder, config);
  }
  std::vector<std::string> problems;
  std::vector<EvalRow> rows = ReadRuns(runs_path, &problems);
  // Rows whose configuration cannot be checked are not taken as this one's.
  if (!checked && !rows.empty())
    throw InputError::Flag(
        "--out", out_dir + " holds " + std::to_string(rows.size()) +
                     " rows in runs.csv but no effective.yaml to check "
                     "them against: put back the effective.yaml of the "
                     "run that made them, or use a new folder");
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
  WriteFileAtomic(effective_path, EvalConfigText(merged));
  return rows;
}

RowSink::RowSink(const EvalOptions& o, const std::vector<std::string>& policies,
                 std::vector<EvalRow> rows, int total_runs, bool root,
                 Ranks* ranks)
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
  if (fd_ < 0) ThrowCannotWriteErrno(runs_path_, errno);
  ::fcntl(fd_, F_SETFL, ::fcntl(fd_, F_GETFL) & ~O_NONBLOCK);
}
RowSink::~RowSink() {
  if (fd_ >= 0) ::close(fd_);
}

void RowSink::Record(const EvalRow& row) {
  const std::string line = CsvLine(row);
  if (!root_) {
    ranks_->SendLine(line);
    return;
  }
  errno = 0;
  if (::write(fd_, line.data(), line.size()) !=
      static_cast<ssize_t>(line.size()))
    ThrowCannotWriteErrno(runs_path_, errno);
  // Kept as the file holds it (its columns rounded), so that summary.csv
  // is the same whether the rows were run now or read by a resume.
  EvalRow written;
  AIA_CHECK(ParseCsvLine(line.substr(0, line.size() - 1), &written));
  rows_.push_back(written);
  ++finished_;
  char buf[200];
  std::snprintf(buf, sizeof(buf), "[aia eval] %d/%d runs  (last: %s seed %llu)",
                finished_, total_runs_, row.size.c_str(),
                static_cast<unsigned long long>(row.seed));
  progress_.Update(buf);
}

void RowSink::Flush() {
  progress_.Finish();
  if (fd_ >= 0) ::fsync(fd_);
}

std::string RowSink::WriteResults() {
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
    if (std::find(policies.begin(), policies.end(), r.policy) == policies.end())
      policies.push_back(r.policy);
  }
  const std::string summary = SummaryCsv(rows_, all_sizes, policies);
  WriteFileAtomic(options_.out_dir + "/summary.csv", summary);
  coverage_ = Coverage(all_sizes, policies);
  return summary;
}

std::string RowSink::Coverage(const std::vector<std::string>& sizes,
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

}  // namespace aia
