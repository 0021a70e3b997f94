// `aia eval`: the scalability experiment of SPEC section 9. For each size and
// seed it generates the world, runs the expert for F*, runs each policy to
// success or 3 F* steps, and writes DIR/runs.csv (one row per instance and
// policy) and DIR/summary.csv (per size and policy: success rate and mean
// flowtime increase, a failure counting F = 3 F*). Instances run in parallel;
// finished rows are kept, so an interrupted eval resumes where it stopped.
#ifndef AIA_RUNTIME_EVAL_H_
#define AIA_RUNTIME_EVAL_H_

#include <cstdint>
#include <string>
#include <vector>

namespace aia {

struct EvalOptions {
  std::vector<std::string> sizes{"10x10", "20x20"};
  int seeds = 100;
  std::uint64_t seed_base = 0;
  std::vector<std::string>
      policies;  // empty: every registered policy but the expert
  std::string out_dir;
  int threads = 0;  // 0: all cores
  bool progress = true;
};

// One row of runs.csv.
struct EvalRow {
  std::string size;
  std::uint64_t seed = 0;
  std::string policy;
  bool success = false;
  int flowtime = -1;  // steps to success, -1 when not reached within 3 F*
  int fstar = -1;     // the expert's F*, -1 when the expert found no plan
  double wall_s = 0.0;
};

// Parses runs.csv (rows that do not parse are dropped, e.g. a line cut short
// by an interruption).
std::vector<EvalRow> ReadRuns(const std::string& path);

// summary.csv text from rows, sizes and policies in the given order.
std::string SummaryCsv(const std::vector<EvalRow>& rows,
                       const std::vector<std::string>& sizes,
                       const std::vector<std::string>& policies);

int RunEval(const EvalOptions& options);

}  // namespace aia

#endif  // AIA_RUNTIME_EVAL_H_
