// `aia eval` at work (eval.h): the runs left in the folder (eval_folder.h),
// shared among the MPI ranks, run on a thread pool, their rows recorded as
// they finish; Ctrl-C writes what is done.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "aia/commands/eval.h"
#include "aia/commands/eval_folder.h"
#include "aia/commands/ranks.h"
#include "aia/core/error.h"
#include "aia/core/field_io.h"
#include "aia/core/interrupt.h"
#include "aia/core/io.h"
#include "aia/core/thread_pool.h"
#include "aia/runtime/mission.h"
#include "aia/runtime/outputs.h"
#include "aia/runtime/policies.h"

namespace aia {
namespace {

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

// The flags that need no scenario (their declarations: `--flag: what`) and
// the output folder.
void CheckEvalFlags(const EvalOptions& o) {
  EvalOptions flags = o;
  CheckFlags(&flags);
  if (o.out_dir.empty())
    throw InputError::Flag("--out", "an output folder is required");
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
      throw InputError::Flag(
          "name", "'" + extra->name() +
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
      rows = ResumeFolder(o.out_dir, EvalConfig(setup, instances.front()));
    } catch (...) {
      ranks.AgreeFromRoot(false);  // the other ranks stop quietly
      throw;
    }
  }
  if (!ranks.AgreeFromRoot(true)) return 2;
  if (!root) rows = ReadRuns(o.out_dir + "/runs.csv");
  // Rank 0 appends to runs.csv from now on: every rank reads the rows
  // resumed first, or the shares of the work left would differ (a rank
  // that read rank 0's first new rows ran rank 0's share, and its own was
  // never run).
  ranks.Barrier();
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
    if (o.started) o.started();
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
