#include "aia/runtime/observers.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>

#include "aia/core/check.h"
#include "aia/core/io.h"

namespace aia {

struct TraceObserver::Impl {
  AtomicFile file;
  std::string row;
  bool robot_columns = true;
  bool time_column = false;
  explicit Impl(const std::string& path) : file(path) {}
};

namespace {

// ",v" with `precision` digits after the point, in `format`, as printf
// writes it in the C locale (std::to_chars: the same digits whatever the
// process's LC_NUMERIC, and five times faster; a trace of 1000 x 1000
// writes a million numbers a step).
void AppendReal(double v, std::chars_format format, int precision,
                std::string* row) {
  char buf[400];
  buf[0] = ',';
  const auto r =
      std::to_chars(buf + 1, buf + sizeof(buf), v, format, precision);
  AIA_CHECK(r.ec == std::errc());
  row->append(buf, r.ptr);
}

// ",%.6e".
void AppendScientific(double v, std::string* row) {
  AppendReal(v, std::chars_format::scientific, 6, row);
}

}  // namespace

TraceObserver::TraceObserver(const std::string& path, int num_robots,
                             bool robot_columns, bool time_column)
    : impl_(std::make_unique<Impl>(path)) {
  impl_->robot_columns = robot_columns;
  impl_->time_column = time_column;
  std::string header =
      time_column ? "step,time,target,min_det" : "step,target,min_det";
  if (robot_columns)
    for (int i = 0; i < num_robots; ++i) header += ",det_r" + std::to_string(i);
  header += "\n";
  std::fputs(header.c_str(), impl_->file.get());
}

TraceObserver::~TraceObserver() = default;

void TraceObserver::Write(const Episode& e) {
  const int n = impl_->robot_columns ? e.world().NumRobots() : 0;
  for (int k = 0; k < e.world().NumTargets(); ++k) {
    std::string& row = impl_->row;
    row.clear();
    row += std::to_string(e.filter_step());
    if (impl_->time_column)
      AppendReal(e.clock_seconds(), std::chars_format::fixed, 3, &row);
    row += ',';
    row += std::to_string(k);
    // With no robot active there is no minimum: the field is empty (as
    // summary.json's final_min_det is null), never "inf".
    const double min_det = e.MinDet(k);
    if (std::isfinite(min_det)) {
      AppendScientific(min_det, &row);
    } else {
      row += ',';
    }
    for (int i = 0; i < n; ++i) AppendScientific(e.Det(i, k), &row);
    row += '\n';
    std::fwrite(row.data(), 1, row.size(), impl_->file.get());
  }
}

void TraceObserver::OnEnd(const Episode&) { impl_->file.Commit(); }

namespace {

// |mu - x| of the position and (x - mu)' Omega (x - mu), on fixed-size
// blocks (no allocation per step).
template <int D>
void ErrorAndNees(const BeliefSet& b, int robot, int k,
                  const Eigen::VectorXd& x, double* error, double* nees) {
  const Eigen::Matrix<double, D, D> omega = b.Omega(robot, k);
  const Eigen::Matrix<double, D, 1> xi = b.Xi(robot, k);
  const Eigen::Matrix<double, D, 1> err = x.head<D>() - omega.llt().solve(xi);
  *error = err.template head<2>().norm();
  *nees = err.dot(omega * err);
}

}  // namespace

struct EstimateObserver::Impl {
  AtomicFile file;
  std::string row;
  explicit Impl(const std::string& path) : file(path) {
    std::fputs("step,target,robot,error_m,nees\n", file.get());
  }
};

EstimateObserver::EstimateObserver(const std::string& csv_path) {
  if (!csv_path.empty()) impl_ = std::make_unique<Impl>(csv_path);
}

EstimateObserver::~EstimateObserver() = default;

void EstimateObserver::Score(const Episode& e) {
  const int m = e.world().NumTargets();
  if (sum_sq_.empty()) {
    sum_sq_.assign(m, 0.0);
    sum_nees_.assign(m, 0.0);
  }
  const BeliefSet& b = e.beliefs();
  for (int k = 0; k < m; ++k) {
    // With every robot failed, robot 0's belief (kept, predicted alone).
    const int robot = std::max(0, e.BestRobot(k));
    const Eigen::VectorXd& x = e.target_states()[k];
    double error = 0.0, nees = 0.0;
    if (x.size() == 2) {
      ErrorAndNees<2>(b, robot, k, x, &error, &nees);
    } else {
      ErrorAndNees<4>(b, robot, k, x, &error, &nees);
    }
    sum_sq_[k] += error * error;
    sum_nees_[k] += nees;
    if (impl_) {
      std::string& row = impl_->row;  // its memory kept, as the trace's
      row.clear();
      row += std::to_string(e.filter_step());
      row += ',';
      row += std::to_string(k);
      row += ',';
      row += std::to_string(robot);
      AppendScientific(error, &row);
      AppendScientific(nees, &row);
      row += '\n';
      std::fwrite(row.data(), 1, row.size(), impl_->file.get());
    }
  }
  ++samples_;
}

void EstimateObserver::OnEnd(const Episode&) {
  if (impl_) impl_->file.Commit();
}

double EstimateObserver::rmse(int k) const {
  return samples_ ? std::sqrt(sum_sq_[k] / samples_) : 0.0;
}

double EstimateObserver::mean_nees(int k) const {
  return samples_ ? sum_nees_[k] / samples_ : 0.0;
}

double EstimateObserver::rmse() const {
  double s = 0.0;
  for (double v : sum_sq_) s += v;
  return samples_ && !sum_sq_.empty()
             ? std::sqrt(s / (samples_ * static_cast<double>(sum_sq_.size())))
             : 0.0;
}

double EstimateObserver::mean_nees() const {
  double s = 0.0;
  for (double v : sum_nees_) s += v;
  return samples_ && !sum_nees_.empty()
             ? s / (samples_ * static_cast<double>(sum_nees_.size()))
             : 0.0;
}

ProgressObserver::ProgressObserver(std::string label, bool enabled,
                                   std::function<std::string()> extra)
    : label_(std::move(label)), line_(enabled), extra_(std::move(extra)) {}

ObserverStatus ProgressObserver::OnStep(const Episode& e) {
  char buf[160];
  std::snprintf(buf, sizeof(buf), "[%s] %s  step %d/%d  localized %d/%d",
                label_.c_str(), std::string(e.policy().name()).c_str(),
                e.step(), e.mission().max_steps, e.NumLocalized(),
                e.world().NumTargets());
  line_.Update(extra_ ? std::string(buf) + "  " + extra_() : std::string(buf));
  return ObserverStatus::kContinue;
}

void ProgressObserver::OnEnd(const Episode&) { line_.Finish(); }

void MoveObserver::OnStart(const Episode&) {
  moves_ = reversals_ = stays_ = 0;
  longest_run_ = 0;
}

ObserverStatus MoveObserver::OnDecision(const Episode&,
                                        const DecisionContext& ctx,
                                        const Decision& decision) {
  for (std::size_t i = 0; i < decision.wanted.size(); ++i) {
    const int r = static_cast<int>(i);
    if (decision.ready && !(*decision.ready)[i]) continue;  // on its way
    if (decision.wanted[i] == Move::kStay && ctx.comm->Active(r)) ++stays_;
  }
  return ObserverStatus::kContinue;
}

ObserverStatus MoveObserver::OnStep(const Episode& e) {
  Count(e);
  return ObserverStatus::kContinue;
}

// The episode's history counts every lattice move as it is made (in async,
// moves end between sensing ticks).
void MoveObserver::Count(const Episode& e) {
  const MoveHistory& h = e.history();
  moves_ = h.moves();
  reversals_ = h.total_reversals();
  longest_run_ = h.longest_run();
}

}  // namespace aia
