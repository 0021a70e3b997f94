// The step observers every mission command attaches (runtime/episode.h):
// the trace of det Sigma, the estimate's error against the truth, and the
// progress line.
#ifndef AIA_RUNTIME_OBSERVERS_H_
#define AIA_RUNTIME_OBSERVERS_H_

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "aia/core/progress.h"
#include "aia/runtime/episode.h"

namespace aia {

// Streams trace.csv, atomically (committed at the end): one row per filter
// step and target: step, target, min over active robots of det Sigma, and
// each robot's det Sigma.
class TraceObserver : public StepObserver {
 public:
  // With robot_columns, each row also holds every robot's det Sigma_i^k
  // (det_r0, det_r1, ...): N x M numbers a step. With time_column (async
  // decisions, whose sensing ticks are not decision steps) the simulated
  // clock in seconds follows the step: step,time,target,...
  TraceObserver(const std::string& path, int num_robots,
                bool robot_columns = true, bool time_column = false);
  ~TraceObserver() override;
  void OnStart(const Episode& e) override { Write(e); }
  ObserverStatus OnStep(const Episode& e) override {
    Write(e);
    return ObserverStatus::kContinue;
  }
  void OnEnd(const Episode& e) override;

 private:
  void Write(const Episode& e);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Scores the team's best estimate of each target (the belief of the active
// robot with the smallest det Sigma_k) against the truth, every step: the
// position error |mu - x| and the normalized estimation error squared
// NEES = (x - mu)' Omega (x - mu) over the target's whole state (about its
// dimension on average for a consistent filter). Streams estimate.csv (step,
// target, robot, error_m, nees) when given a path.
class EstimateObserver : public StepObserver {
 public:
  explicit EstimateObserver(const std::string& csv_path = "");
  ~EstimateObserver() override;
  void OnStart(const Episode& e) override { Score(e); }
  ObserverStatus OnStep(const Episode& e) override {
    Score(e);
    return ObserverStatus::kContinue;
  }
  void OnEnd(const Episode& e) override;

  // Over every step and target so far: sqrt(mean error^2), and mean NEES.
  double rmse() const;
  double mean_nees() const;
  // Per target.
  double rmse(int target) const;
  double mean_nees(int target) const;
  int num_targets() const { return static_cast<int>(sum_sq_.size()); }

 private:
  void Score(const Episode& e);
  std::vector<double> sum_sq_, sum_nees_;
  long samples_ = 0;  // steps scored
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Counts the lattice moves the robots made (Episode::moves_made: a stalled
// robot made none) and the reversals among them (a move that undoes the same
// robot's previous one; planning/policy.h, IsReversal, as the policies see
// it), and the longest run of back-to-back reversals of one robot (a robot
// shuttling between two points for r steps makes a run of r - 1).
// It also counts the stays the policy chose for active robots.
class MoveObserver : public StepObserver {
 public:
  void OnStart(const Episode& e) override;
  ObserverStatus OnDecision(const Episode& e, const DecisionContext& ctx,
                            const Decision& decision) override;
  ObserverStatus OnStep(const Episode& e) override;
  void OnEnd(const Episode& e) override { Count(e); }

  long moves() const { return moves_; }
  long reversals() const { return reversals_; }
  long stays() const { return stays_; }
  int longest_reversal_run() const { return longest_run_; }

 private:
  void Count(const Episode& e);
  long moves_ = 0, reversals_ = 0, stays_ = 0;
  int longest_run_ = 0;
};

// "[aia run] greedy  step 12/400  localized 3/10" after every step, plus
// `extra()` when given (frames rendered, ...).
class ProgressObserver : public StepObserver {
 public:
  ProgressObserver(std::string label, bool enabled,
                   std::function<std::string()> extra = {});
  ObserverStatus OnStep(const Episode& e) override;
  void OnEnd(const Episode& e) override;

 private:
  std::string label_;
  ProgressLine line_;
  std::function<std::string()> extra_;
};

}  // namespace aia

#endif  // AIA_RUNTIME_OBSERVERS_H_
