// `aia eval`: the scalability experiment (docs/design.md, Evaluation), in three
// pieces so that a sweep can be spread over processes (MPI ranks, ranks.h,
// only hand out instances):
//   1. EnumerateInstances: every (size, seed) of the experiment;
//   2. RunInstance: one instance, a pure function of the instance and the
//      setup: the world is built once, the expert's F* computed, then each
//      policy runs to success or 3 F* steps on that same world;
//   3. SummaryCsv: rows merged into success rates and flowtime increases.
// RunEval (eval_run.cc) drives them on a thread pool into an output folder
// (eval_folder.h: DIR/runs.csv, appended as runs finish so that an
// interrupted eval resumes, DIR/summary.csv and DIR/effective.yaml).
#ifndef AIA_COMMANDS_EVAL_H_
#define AIA_COMMANDS_EVAL_H_

#include <algorithm>
#include <cstdint>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "aia/core/csv.h"
#include "aia/core/field_values.h"
#include "aia/planning/expert.h"
#include "aia/planning/registry.h"
#include "aia/runtime/generated.h"
#include "aia/scenario/config.h"
#include "aia/scenario/loader.h"

namespace aia {

// One world of the experiment.
struct EvalInstance {
  std::string size;  // its label, e.g. "10x10" (TeamSize::ToText)
  int robots = 0;
  int targets = 0;
  std::uint64_t seed = 0;
};

// The worlds one evaluation takes at most (sizes x seeds): each is a C-SB
// solve and a mission per policy (tens of ms at the least), so a million is
// days of work; more would first fill the memory with their list.
inline constexpr std::uint64_t kMaxEvalWorlds = 1000000;

// Sizes in the given order, seeds seed_base .. seed_base + seeds - 1;
// InputError naming --seed-base when the last seed would pass 2^64 - 1, or
// --seeds when there are more than kMaxEvalWorlds.
std::vector<EvalInstance> EnumerateInstances(const std::vector<TeamSize>& sizes,
                                             int seeds,
                                             std::uint64_t seed_base);

// What every instance shares: the scenario overrides, the evaluated policies
// (resolved once: parameters checked, resources loaded) and the expert that
// gives F*.
struct EvalSetup {
  std::vector<Override> overrides;  // scenario keys other than policy.*
  std::vector<std::shared_ptr<const PolicySpec>> policies;
  std::shared_ptr<const PolicySpec> expert;
};

// `sets` are --set flags: policy.<param> goes to every policy (the expert of
// F* included) that declares the parameter, and is bad input if none does;
// seed, robots.count and targets.count belong to the instances. The
// overrides are checked, before any work, on the first instance of each
// size of `instances` (on a 1x1 world at seed 0 when there are none); an
// error names the flag at fault (NameTheFlag).
EvalSetup MakeEvalSetup(const std::vector<std::string>& policies,
                        const std::vector<std::string>& sets,
                        const PolicyRegistry& registry,
                        const std::vector<EvalInstance>& instances = {});

// The horizon of an instance and the denominator of its flowtime increase:
// 3 F* steps, with F* = 0 (targets all localized at the start) counted as 1
// so that the ratio is defined.
inline int EvalHorizon(int fstar) { return 3 * std::max(fstar, 1); }

// One row of runs.csv.
struct EvalRow {
  std::string size;
  std::uint64_t seed = 0;
  std::string policy;
  bool success = false;
  int flowtime = -1;  // steps to success, -1 when not reached within 3 F*
  int fstar = -1;     // the expert's F*, -1 when the expert found no plan
  int bound = 0;      // the expert's lower bound on the horizon
  // Back-and-forth: the share of the robots' moves that undo their previous
  // move, and the most consecutive such moves of one robot (MoveObserver).
  double reversal_share = 0.0;
  int longest_reversal_run = 0;
  // Simulated seconds until success (or until the run stopped), and the
  // robot-steps that ended stalled short of the waypoint or at the timeout.
  double mission_seconds = 0.0;
  long stalls = 0;
  long timeouts = 0;
  double wall_s = 0.0;

  // runs.csv's columns, declared once (core/csv.h): header, writer and
  // reader.
  template <typename C>
  void Columns(C* c) {
    c->Column("size", &size);
    c->Column("seed", &seed);
    c->Column("policy", &policy);
    c->Column("success", &success);
    c->Column("flowtime", &flowtime, CsvFormat::EmptyIs(-1));
    c->Column("fstar", &fstar);
    c->Column("bound", &bound);
    c->Column("reversal_share", &reversal_share, CsvFormat::Fixed(4));
    c->Column("longest_reversal_run", &longest_reversal_run);
    c->Column("mission_seconds", &mission_seconds, CsvFormat::Fixed(3));
    c->Column("stalls", &stalls);
    c->Column("timeouts", &timeouts);
    c->Column("wall_s", &wall_s, CsvFormat::Fixed(4));
  }
};

// How an instance's scenario is generated (with "--sizes" as its flag).
GeneratedSpec InstanceSpec(const EvalInstance& instance,
                           const EvalSetup& setup);
// The scenario of an instance: the generated one with the setup's overrides
// (ReadGenerated).
Scenario InstanceScenario(const EvalInstance& instance, const EvalSetup& setup);

// Thrown by RunInstance when Ctrl-C cut a run short (core/interrupt.h): its
// row would read as a failure, so there is none.
struct RunInterrupted : std::exception {
  const char* what() const noexcept override { return "interrupted"; }
};

// Runs `policies` (a subset of setup.policies, by name; empty: all) on one
// instance, in that order. Rows do not depend on anything else (wall_s
// aside). RunInterrupted when Ctrl-C ends a run early.
std::vector<EvalRow> RunInstance(const EvalInstance& instance,
                                 const EvalSetup& setup,
                                 const std::vector<std::string>& policies = {});

// summary.csv text from rows, sizes and policies in the given order.
// One row of summary.csv: a size and a policy over the instances with an
// expert plan (no figures, empty cells, when there is none).
struct SummaryRow {
  std::string size, policy;
  int instances = 0;
  double success_rate = kNaN, flowtime_increase = kNaN, mean_flowtime = kNaN,
         mean_fstar = kNaN, mean_fstar_over_bound = kNaN;
  int no_expert_plan = 0;
  double reversal_share = kNaN;
  int longest_reversal_run = -1;
  // Means over the runs: simulated seconds (a failure's until it stopped),
  // stalled and timed-out robot-steps.
  double mission_seconds = kNaN, stalls = kNaN, timeouts = kNaN;

  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  // summary.csv's columns, declared once (core/csv.h).
  template <typename C>
  void Columns(C* c) {
    c->Column("size", &size);
    c->Column("policy", &policy);
    c->Column("instances", &instances);
    c->Column("success_rate", &success_rate, CsvFormat::Fixed(4, true));
    c->Column("flowtime_increase", &flowtime_increase,
              CsvFormat::Fixed(4, true));
    c->Column("mean_flowtime", &mean_flowtime, CsvFormat::Fixed(3, true));
    c->Column("mean_fstar", &mean_fstar, CsvFormat::Fixed(3, true));
    c->Column("mean_fstar_over_bound", &mean_fstar_over_bound,
              CsvFormat::Fixed(4, true));
    c->Column("no_expert_plan", &no_expert_plan);
    c->Column("reversal_share", &reversal_share, CsvFormat::Fixed(4, true));
    c->Column("longest_reversal_run", &longest_reversal_run,
              CsvFormat::EmptyIs(-1));
    c->Column("mission_seconds", &mission_seconds, CsvFormat::Fixed(3, true));
    c->Column("stalls", &stalls, CsvFormat::Fixed(3, true));
    c->Column("timeouts", &timeouts, CsvFormat::Fixed(3, true));
  }
};

std::string SummaryCsv(const std::vector<EvalRow>& rows,
                       const std::vector<std::string>& sizes,
                       const std::vector<std::string>& policies);

struct EvalOptions {
  std::vector<TeamSize> sizes{{10, 10}, {20, 20}};
  int seeds = 100;
  std::uint64_t seed_base = 0;
  std::vector<std::string>
      policies;  // empty: every registered policy but the expert
  std::vector<std::string> sets;  // --set key.path=value
  std::string out_dir;
  int threads = 0;  // 0: all cores
  bool progress = true;
  // Policies not in the registry, scored after `policies` (the Python
  // package's evaluate); their names must not be registered ones.
  std::vector<std::shared_ptr<const PolicySpec>> extra_policies;
  // Ctrl-C: true (the CLI) ends the process once the finished rows are
  // written, abandoning the runs in flight; false waits for them to stop at
  // their next step, then returns kInterruptedExitCode.
  bool exit_on_interrupt = true;
  // Called once (by the process that writes runs.csv) when the inputs are
  // checked and the folder resumed, before the first run: aia.evaluate
  // draws its bar then, not before a refusal.
  std::function<void()> started;

  // The flags that need no scenario, declared once for `aia eval`'s flags
  // and their checks.
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(sizes).Doc("robots x targets, e.g. 10x10,20x20"));
    a->Visit(AIA_FIELD(seeds).In(AtLeast(1)).Doc("worlds per size"));
    a->Visit(AIA_FIELD(seed_base).Doc("first seed (seeds B .. B+n-1)"));
    a->Visit(AIA_FIELD(policies).Doc(
        "policies to score (default: every registered one but the expert)"));
    a->Visit(AIA_FIELD(threads)
                 .In(AtLeast(0))
                 .Doc("worker threads per process (0: all cores, shared among "
                      "the MPI ranks on a machine)"));
  }
  // At least one size; sizes and policies listed once (one listed twice
  // would write every row twice, and each resume would drop both copies and
  // run them again); the last seed fits in 64 bits.
  void Validate(const FieldChecker& c) const;
};

int RunEval(const EvalOptions& options);

}  // namespace aia

#endif  // AIA_COMMANDS_EVAL_H_
