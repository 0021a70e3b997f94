// The output folder of `aia eval` (eval.h runs the instances) and its
// resume:
//   DIR/runs.csv        one row per instance and policy, appended as runs
//                       finish, so that an interrupted eval resumes;
//   DIR/summary.csv     the rows merged (SummaryCsv);
//   DIR/effective.yaml  the configuration the rows were made with, as YAML
//                       that parses back to the same tree: a `policies:`
//                       mapping (each evaluated policy's parameters, a
//                       learned one's model file by path and SHA-256) and
//                       the scenario keys every instance shares (its policy
//                       section is the expert that gives F*).
// A folder whose configuration differs from the run's is refused, compared
// as configuration trees; a folder of an older aia, whose effective.yaml
// lists the policies in comment lines (`#   NAME: {...}; model PATH sha256
// HEX`), still reads and resumes.
#ifndef AIA_COMMANDS_EVAL_FOLDER_H_
#define AIA_COMMANDS_EVAL_FOLDER_H_

#include <cstddef>
#include <mutex>
#include <string>
#include <vector>

#include "aia/commands/eval.h"
#include "aia/core/config_node.h"
#include "aia/runtime/observers.h"

namespace aia {

class Ranks;

// Parses runs.csv. Rows that do not parse (e.g. a line cut short by an
// interruption), hold impossible values (a negative flowtime, a success
// beyond the horizon) or repeat a run (every copy) are dropped, each with a
// "line N: why" in `problems` when given. The file is read line by line; a
// line longer than 64 KiB (a file cut by a crash may end in gigabytes of
// NULs), a FIFO or a device is InputError naming --out, the file and the
// line.
std::vector<EvalRow> ReadRuns(const std::string& path,
                              std::vector<std::string>* problems = nullptr);

// The configuration of a run as effective.yaml's tree: `policies:` (NAME ->
// its parameters, plus `model` and `model_sha256` for a learned policy, as
// the scenario's policy section names them), then every scenario key of a
// 1x1 world at seed 0 with the overrides (of the first instance when the
// overrides fit only the sizes given), its policy the expert of F*.
ConfigNode EvalConfig(const EvalSetup& setup, const EvalInstance& first);

// effective.yaml's text: a header comment, then the tree.
std::string EvalConfigText(const ConfigNode& config);

// An effective.yaml read back as EvalConfig's tree, whether this aia wrote
// it or an older one (policies in comment lines; their parameters as
// written, a model after "; model "). InputError at `file` and the line when
// it is not YAML or `policies` is not a mapping of mappings.
ConfigNode ReadEvalConfig(const std::string& text, const std::string& file);

// Why a folder's configuration (ReadEvalConfig) does not fit a run's, or "":
// the scenario keys differ, or a policy of both has other parameters or
// another model file (its path or its SHA-256). A policy of one of them
// alone fits.
std::string ConfigMismatch(const ConfigNode& folder, const ConfigNode& run);

// The run's configuration with the folder's policies that it does not list,
// after its own: the rows of those policies stay in the folder.
ConfigNode WithFolderPolicies(const ConfigNode& folder, const ConfigNode& run);

// Rank 0's resume: locks the output folder, refuses one that holds results
// of another configuration (InputError naming --out), keeps the rows
// already there (a row cut short by an interruption, garbled, impossible or
// duplicated is reported on stderr, dropped and run again), rewrites
// runs.csv cleanly and writes effective.yaml (the run's configuration and
// the folder's other policies).
std::vector<EvalRow> ResumeFolder(const std::string& out_dir,
                                  const ConfigNode& config);

// Where finished rows go. On rank 0 each is appended to runs.csv as it
// finishes (its own, and those the other ranks send), so that an
// interrupted eval loses only the runs in flight; the other ranks send
// theirs to rank 0. Record() and WriteResults() are called under mutex().
class RowSink {
 public:
  // `rows`: those already in the folder; `total_runs`: the runs to come, of
  // every rank (for the progress line).
  RowSink(const EvalOptions& o, const std::vector<std::string>& policies,
          std::vector<EvalRow> rows, int total_runs, bool root, Ranks* ranks);
  ~RowSink();
  RowSink(const RowSink&) = delete;
  RowSink& operator=(const RowSink&) = delete;

  std::mutex& mutex() { return mu_; }
  const std::string& runs_path() const { return runs_path_; }
  std::size_t rows() const { return rows_.size(); }

  void Record(const EvalRow& row);
  // The appended rows on disk, and the progress line ended.
  void Flush();
  // runs.csv rewritten in canonical order (so that the files do not depend
  // on the thread count) and summary.csv of every row of the folder; returns
  // the summary.
  std::string WriteResults();
  // What summary.csv covers, for the last line of the command: "all 24 rows
  // of runs.csv: sizes 2x2, 3x3; seeds 0 to 5; policies greedy, random".
  const std::string& coverage() const { return coverage_; }

 private:
  std::string Coverage(const std::vector<std::string>& sizes,
                       const std::vector<std::string>& policies) const;

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
};

}  // namespace aia

#endif  // AIA_COMMANDS_EVAL_FOLDER_H_
