#include "aia/estimation/filter.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <mutex>
#include <string>

#include "aia/core/check.h"
#include "aia/core/fields.h"
#include "aia/core/repeated_sum.h"
#include "spd.h"

namespace aia {
namespace {

template <int D>
using MatD = Eigen::Matrix<double, D, D>;
template <int D>
using VecD = Eigen::Matrix<double, D, 1>;
using RowMap = Eigen::Map<Eigen::ArrayXd>;
using ConstRowMap = Eigen::Map<const Eigen::ArrayXd>;

// Omega_{t+1|t} = (A Sigma A' + q I)^-1 from Sigma = Omega_{t|t}^-1, through
// the moment form: the information form has no cheaper exact time update
// when A is not the identity. A predicted variance above kMaxVariance is
// scaled down to that bound, and the return value says so (the filter
// decides whether that is a divergence: Predict); a variance that is not
// finite throws EstimateDiverged.
template <int D>
bool PredictOmega(const TargetModel& model, const MatD<D>& sigma,
                  Eigen::Map<MatD<D>> omega) {
  const Eigen::Map<const MatD<D>> a(model.A.data());
  MatD<D> sigma_pred =
      a * sigma * a.transpose() + model.q * MatD<D>::Identity();
  const double top = sigma_pred.diagonal().maxCoeff();
  const bool beyond = !(top <= kMaxVariance);
  if (beyond) {
    if (!std::isfinite(top)) {
      throw EstimateDiverged(-1, "its predicted variance reaches " +
                                     FormatNumber(top) + " m^2, beyond " +
                                     FormatNumber(kMaxVariance));
    }
    sigma_pred *= kMaxVariance / top;
  }
  // A variance that contracting noiseless dynamics drive toward zero stays
  // a normal double (a no-op for any variance above ~1e-14).
  if (sigma_pred.diagonal().minCoeff() < kMinVariance)
    sigma_pred.diagonal().array() += kMinVariance;
  const MatD<D> omega_pred = internal::InverseSpd<D>(sigma_pred);
  // The DKF sums these blocks across robots every step; any asymmetry left
  // here would be carried (and compounded by prediction) forever.
  omega = 0.5 * (omega_pred + omega_pred.transpose());
  return beyond;
}

// x_{t+1|t} for one target block: Omega as above, xi = Omega (A mu + b);
// whether the variance was scaled back (PredictOmega) or the mean: each
// entry held within kMaxMean (an unstable target's mean doubles a step in a
// belief that nothing measures, and overflowed after some 1000 steps). For
// the filter (`filter`), a mean that is not finite even so is a divergence.
template <int D>
bool PredictBlock(const TargetModel& model, double* block, bool filter) {
  Eigen::Map<MatD<D>> omega(block);
  Eigen::Map<VecD<D>> xi(block + D * D);
  const Eigen::Map<const MatD<D>> a(model.A.data());
  const Eigen::Map<const VecD<D>> b(model.b.data());
  const MatD<D> sigma = internal::InverseSpd<D>(omega);
  const VecD<D> mu = sigma * xi;
  bool beyond = PredictOmega<D>(model, sigma, omega);
  VecD<D> mu_pred = a * mu + b;
  if (mu_pred.cwiseAbs().maxCoeff() > kMaxMean) {
    mu_pred = mu_pred.cwiseMax(-kMaxMean).cwiseMin(kMaxMean);
    beyond = true;
  }
  if (filter && !mu_pred.allFinite())
    throw EstimateDiverged(-1, "its predicted mean is not finite");
  xi = omega * mu_pred;
  return beyond;
}

// Row i of the DKF's weights as MixRows takes it: uniform rows (the DKF's,
// as FusionWeights makes them) are self * B_i + off * sum_{j in nb} B_j with
// nb ascending and i excluded; other rows (a general W) are a dense row.
struct RowWeights {
  bool uniform = true;
  double self = 0.0, off = 0.0;
  const std::vector<int>* nb = nullptr;
  const double* dense = nullptr;  // !uniform: W(i, 0..n-1), strided
  Eigen::Index stride = 1;
};

// A row worth the sum trick: its neighbours are the majority of the team, so
// S - (the few non-neighbours) is cheaper than adding the neighbours; and
// its own row is in S (`counted`, below).
bool IsDenseUniform(const RowWeights& r, int n, bool counted) {
  return r.uniform && counted && 2 * static_cast<int>(r.nb->size()) > n;
}

// counted[j]: whether row j is some uniform row's neighbour, so part of the
// column sum S. Rows that are nobody's neighbour (a failed robot's, an
// isolated one's) are left out of S, not subtracted again from every row:
// with F of them that was F x N x M work a step (cubic as failures grow
// with the team: 279 ms of fusion at 1000 robots with 100 failed, 33 with
// none), and a subtraction that cancels where they hold most of the
// information. Stops as soon as every row is counted (the full graph: after
// two rows). How many rows are counted.
int CountRows(const std::vector<RowWeights>& w,
              std::vector<std::uint8_t>* counted) {
  const int n = static_cast<int>(w.size());
  counted->assign(n, 0);
  int count = 0;
  for (int i = 0; i < n && count < n; ++i) {
    if (!w[i].uniform) continue;
    for (int j : *w[i].nb) {
      count += (*counted)[j] == 0;
      (*counted)[j] = 1;
    }
  }
  return count;
}

// Rows of the N x stride belief matrices, as contiguous arrays (the storage
// is row-major) so that every pass below is one vectorized loop; or the
// columns [c0, c0 + width) of each row (one target's block).
struct RowPair {
  const BeliefSet::Storage& b;
  BeliefSet::Storage& out;
  Eigen::Index c0 = 0, width = b.cols();

  ConstRowMap In(int j) const { return {b.data() + j * b.cols() + c0, width}; }
  RowMap Out(int i) const { return {out.data() + i * out.cols() + c0, width}; }
};

// o += scale * (in(0) + in(1) + ... + in(count - 1)), four terms summed
// in order in one pass over `o`, which saves loads and stores of `o` in a
// loop that is bound by memory traffic.
template <typename In, typename Out>
void AddInFours(const In& in, int count, double scale, Out&& o) {
  const int full = count / 4 * 4;
  for (int c = 0; c < full; c += 4)
    o += scale * (in(c) + in(c + 1) + in(c + 2) + in(c + 3));
  const int rest = count - full;
  if (rest == 3) o += scale * (in(full) + in(full + 1) + in(full + 2));
  if (rest == 2) o += scale * (in(full) + in(full + 1));
  if (rest == 1) o += scale * in(full);
}

// o += scale * sum_j B_j over the rows j = rows(0), rows(1), ..., rows(count
// - 1), in that (ascending) order.
template <typename Rows>
void AddRows(const Rows& rows, int count, const RowPair& m, double scale,
             RowMap o) {
  AddInFours([&](int c) { return m.In(rows(c)); }, count, scale, o);
}

void AddRows(const std::vector<int>& rows, const RowPair& m, double scale,
             RowMap o) {
  AddRows([&](int c) { return rows[c]; }, static_cast<int>(rows.size()), m,
          scale, o);
}

// Calls visit(j) for the counted rows j of a team of n neither in nb
// (ascending) nor i, ascending: the rows a dense row leaves out.
template <typename Visit>
void ForLeftOut(const std::vector<int>& nb, int i,
                const std::vector<std::uint8_t>& counted, int n,
                Visit&& visit) {
  std::size_t next = 0;
  for (int j = 0; j < n; ++j) {
    if (next < nb.size() && nb[next] == j) {
      ++next;
      continue;
    }
    if (j != i && counted[j]) visit(j);
  }
}

// o += scale * sum_j B_j over the counted rows of the team not in nb and
// not i, in ascending order and grouped as AddRows groups them: the same
// numbers, without a list of those rows (nb is ascending). Whether there was
// any.
bool AddExcludedRows(const std::vector<int>& nb, int i,
                     const std::vector<std::uint8_t>& counted, int n_counted,
                     const RowPair& m, double scale, RowMap o) {
  const int n = static_cast<int>(m.b.rows());
  // nb holds every counted row but i (i is counted)
  if (static_cast<int>(nb.size()) == n_counted - 1) return false;
  int pending[4], count = 0;
  ForLeftOut(nb, i, counted, n, [&](int j) {
    pending[count++] = j;
    if (count == 4) {
      AddRows([&](int c) { return pending[c]; }, 4, m, scale, o);
      count = 0;
    }
  });
  AddRows([&](int c) { return pending[c]; }, count, m, scale, o);
  return true;
}

// Where the excluded rows of a dense row hold nearly all of the team's
// information of a target (a robot cut off from the one that measures an
// unstable target, many steps on), S - B_i - sum_excluded cancels: the
// result keeps an error of a few eps * off * S, which can be all of it, or
// more (an Omega that is zero or not positive definite). A diagonal entry
// of the result under kCancelled * off * S (the excluded rows holding about
// 10^9 times the information of the rest, whose error is then at most about
// 1e-6 of the result) marks the block, which is summed directly over the
// neighbours instead. Never met in the missions of the test suites; the
// numbers elsewhere are the sum trick's.
constexpr double kCancelled = 0x1p-30;

void ResumCancelledBlocks(const BeliefLayout& layout, const RowWeights& r,
                          int i, const RowPair& m, const Eigen::ArrayXd& sum) {
  const RowMap o = m.Out(i);
  for (int k = 0; k < layout.num_targets(); ++k) {
    const int d = layout.dim(k), at = layout.omega_offset(k);
    bool cancelled = false;
    for (int e = 0; e < d && !cancelled; ++e) {
      const int diagonal = at + e * d + e;
      cancelled = !(o[diagonal] > kCancelled * r.off * sum[diagonal]);
    }
    if (!cancelled) continue;
    const RowPair block{m.b, m.out, at, d * d + d};
    RowMap ob = block.Out(i);
    ob = r.self * block.In(i);
    AddRows(*r.nb, block, r.off, ob);
  }
}

// Below this many doubles (rows x stride) the DKF's mix and the time update
// run on the calling thread: at 200 robots and static targets (240 000) the
// mix takes well under a millisecond, little more than handing it to
// threads costs.
constexpr Eigen::Index kParallelRows = Eigen::Index{1} << 18;

// `run` for a set of rows x cols doubles from kParallelRows up, else none.
const RangeRunner& SplitFor(Eigen::Index rows, Eigen::Index cols,
                            const RangeRunner& run) {
  static const RangeRunner kSerial;
  return rows * cols >= kParallelRows ? run : kSerial;
}

// Columns summed per index when the column sum S is split over threads
// (a runner takes indices in chunks: learning/network.h's of 16).
constexpr Eigen::Index kSumColumns = 128;

// out = W * B. A dense GEMM costs N^2 * stride multiply-adds whatever the
// graph (and Eigen heap-allocates its packing buffer at this size). The DKF's
// W has one weight c_i per row off the diagonal, so
//   out_i = kappa_ii B_i + c_i sum_{j in N_i} B_j
//         = kappa_ii B_i + c_i (S - B_i - sum_{j not in N_i + i} B_j)
// with the column sum S = sum_j B_j: the first form for few neighbours, the
// second for many; O(N * stride) in all for the full graph, O(edges *
// stride) for a sparse one. General rows take the direct sum. The
// subtraction costs accuracy only when one robot's information dwarfs the
// others': the error is about eps * sum_j |B_j| per element, and where the
// rows left out hold nearly all of it a block is summed directly
// (ResumCancelledBlocks). Each element is
// summed in an order fixed by the row indices, not by cache sizes or threads
// as in a blocked GEMM, so results are reproducible, and the same whether
// `run` splits the rows (and S's columns) over threads or not. `row_done(i)`
// is called on the thread that finished row i. (Tiling the columns for L1
// reuse gained nothing at N = 80.)
template <typename RowDone>
void MixRows(const BeliefLayout& layout, const std::vector<RowWeights>& w,
             const BeliefSet::Storage& b, BeliefSet::Storage* out,
             Eigen::ArrayXd* sum, const RangeRunner& run,
             const RowDone& row_done) {
  const int n = static_cast<int>(b.rows());
  const RowPair m{b, *out};
  const Eigen::Index cols = b.cols();
  const RangeRunner& split = SplitFor(n, cols, run);

  bool dense = false;
  for (int i = 0; i < n && !dense; ++i) dense = IsDenseUniform(w[i], n, true);
  thread_local std::vector<std::uint8_t> counted_storage;
  std::vector<std::uint8_t>& counted = counted_storage;
  int n_counted = n;
  if (dense) {
    n_counted = CountRows(w, &counted);
    sum->resize(cols);
    const int blocks = static_cast<int>((cols + kSumColumns - 1) / kSumColumns);
    RunRange(split, blocks, [&](int b0, int b1, int) {
      const Eigen::Index c0 = b0 * kSumColumns;
      const Eigen::Index width = std::min(cols, b1 * kSumColumns) - c0;
      auto s = sum->segment(c0, width);
      s.setZero();
      bool first = true;
      for (int j = 0; j < n; ++j) {
        if (!counted[j]) continue;
        if (first) {
          s = m.In(j).segment(c0, width);
          first = false;
        } else {
          s += m.In(j).segment(c0, width);
        }
      }
    });
  }

  RunRange(split, n, [&](int i0, int i1, int) {
    for (int i = i0; i < i1; ++i) {
      const RowWeights& r = w[i];
      RowMap o = m.Out(i);
      if (!r.uniform) {
        o.setZero();
        for (int j = 0; j < n; ++j) {
          const double v = r.dense[j * r.stride];
          if (v != 0.0) o += v * m.In(j);
        }
      } else if (dense && IsDenseUniform(r, n, counted[i])) {
        o = r.off * (*sum - m.In(i)) + r.self * m.In(i);
        if (AddExcludedRows(*r.nb, i, counted, n_counted, m, -r.off, o))
          ResumCancelledBlocks(layout, r, i, m, *sum);
      } else {
        o = r.self * m.In(i);
        AddRows(*r.nb, m, r.off, o);
      }
      row_done(i);
    }
  });
}

// The DKF on a shared set (docs/design.md, Estimation), target by target,
// to the bit what MixRows and the measurements give row by row. In a full
// graph every standard row (neighbours: every other counted row; the
// team's one pair of weights) that holds target k's common block gets one
// and the same result, off (S - C) + self C, worked out once; the column
// sum S adds the rows' blocks in ascending row order, runs of the common
// block at once (AddRepeated, the same bits as one addition at a time).
// Only the own blocks and the special rows (other weights, rows left out of
// a neighbourhood) are mixed one by one, each as MixRows mixes it, and kept
// as the row's own where the result is not the common one bit for bit.
// O(M (own blocks + special rows) + N) instead of O(N M) a step.
class SharedMix {
 public:
  // Whether the step suits it: every row uniform, some dense row (so S is
  // summed) and few special rows (a range graph's are most: MixRows).
  bool Plan(const std::vector<RowWeights>& w, int n) {
    if (n < 2) return false;
    n_ = n;
    w_ = &w;
    bool dense = false;
    for (int i = 0; i < n; ++i) {
      if (!w[i].uniform) return false;
      dense = dense || IsDenseUniform(w[i], n, true);
    }
    if (!dense) return false;
    n_counted_ = CountRows(w, &counted_);
    counted_before_.assign(n + 1, 0);
    for (int i = 0; i < n; ++i)
      counted_before_[i + 1] = counted_before_[i] + counted_[i];
    special_.clear();
    is_special_.assign(n, 0);
    has_standard_ = false;
    for (int i = 0; i < n; ++i) {
      const RowWeights& r = w[i];
      const bool full = counted_[i] && IsDenseUniform(r, n, true) &&
                        static_cast<int>(r.nb->size()) == n_counted_ - 1;
      if (full && !has_standard_) {
        self_ = r.self;
        off_ = r.off;
        has_standard_ = true;
      }
      if (!full || r.self != self_ || r.off != off_) {
        special_.push_back(i);
        is_special_[i] = 1;
      }
    }
    if (8 * static_cast<int>(special_.size()) > n) return false;
    // The counted rows a special dense row leaves out (neither in nb nor
    // itself), ascending, once for every target (AddExcludedRows' rows).
    left_out_.resize(special_.size());
    for (std::size_t s = 0; s < special_.size(); ++s) {
      const int i = special_[s];
      const RowWeights& r = w[i];
      std::vector<int>& out = left_out_[s];
      out.clear();
      if (IsDenseUniform(r, n, counted_[i]) &&
          static_cast<int>(r.nb->size()) != n_counted_ - 1)
        ForLeftOut(*r.nb, i, counted_, n, [&](int j) { out.push_back(j); });
    }
    return true;
  }

  // Whether target-by-target work pays for `b`: the blocks mixed one by
  // one (own blocks, and the special rows') at most a quarter of all. A
  // set that shares nothing (after a step row by row) is judged by a few
  // targets' majority blocks; every one of them row by row is three times
  // the row-by-row mix (the blocks of a target are a row apart).
  bool Pays(const BeliefSet& b) const {
    const int m = b.layout().num_targets();
    if (m == 0) return true;
    if (b.sharing()) {
      const std::size_t limit = static_cast<std::size_t>(n_) * m / 4;
      std::size_t own = 0;
      for (int k = 0; k < m && own <= limit; ++k) {
        const std::vector<int>& rows = b.OwnRows(k);
        own += rows.size();
        for (int i : special_)
          own += !std::binary_search(rows.begin(), rows.end(), i);
      }
      return own <= limit;
    }
    const int samples = std::min(m, 8);
    std::size_t differ = 0;
    for (int s = 0; s < samples; ++s) {
      const int k = static_cast<int>(static_cast<long>(s) * m / samples);
      const std::size_t bytes =
          sizeof(double) * b.layout().dim(k) * (b.layout().dim(k) + 1);
      // Boyer-Moore's majority vote over the rows' blocks, then a count.
      int candidate = 0, votes = 0;
      for (int i = 0; i < n_; ++i) {
        if (votes == 0) {
          candidate = i;
          votes = 1;
        } else {
          votes += std::memcmp(b.Block(i, k), b.Block(candidate, k), bytes) == 0
                       ? 1
                       : -1;
        }
      }
      // The blocks that would be own: those apart from the majority's,
      // and every block of a special row.
      for (int i = 0; i < n_; ++i)
        differ += is_special_[i] ||
                  std::memcmp(b.Block(i, k), b.Block(candidate, k), bytes) != 0;
    }
    return 4 * differ <= static_cast<std::size_t>(samples) * n_;
  }

  void Mix(const BeliefSet& b, BeliefSet* out, const RangeRunner& run) {
    const BeliefLayout& layout = b.layout();
    const int m = layout.num_targets();
    if (!out->sharing()) out->StartSharing();
    RunRange(run, m, [&](int k0, int k1, int) {
      thread_local Scratch scratch;
      for (int k = k0; k < k1; ++k) MixTarget(b, k, out, &scratch);
    });
  }

 private:
  struct Scratch {
    Eigen::ArrayXd sum, o;
    std::vector<int> rows, own;
  };
  using Block = Eigen::Map<const Eigen::ArrayXd>;

  // S = the first counted row's block, then += each later counted row's.
  void Sum(const BeliefSet& b, int k, const std::vector<int>& own, int width,
           Eigen::ArrayXd* sum) const {
    double* s = sum->data();
    sum->setZero();
    bool first = true;
    const auto add = [&](const double* v, std::int64_t count) {
      if (count <= 0) return;
      if (first) {
        std::copy_n(v, width, s);
        first = false;
        --count;
      }
      if (count == 1) {
        for (int e = 0; e < width; ++e) s[e] += v[e];
      } else if (count > 1) {
        for (int e = 0; e < width; ++e) s[e] = AddRepeated(s[e], v[e], count);
      }
    };
    const double* common = b.CommonBlock(k);
    int from = 0;  // rows [from, r) hold the common block
    for (int r : own) {
      add(common, counted_before_[r] - counted_before_[from]);
      if (counted_[r]) add(b.Block(r, k), 1);
      from = r + 1;
    }
    add(common, counted_before_[n_] - counted_before_[from]);
  }

  // Row i's block k as MixRows makes it (the sum trick, the rows left out,
  // the direct sum where they cancel; or the direct sum).
  void MixRow(const BeliefSet& b, int k, int i, const Eigen::ArrayXd& sum,
              Eigen::ArrayXd* out) const {
    const RowWeights& r = (*w_)[i];
    const int width = static_cast<int>(sum.size());
    Eigen::ArrayXd& o = *out;
    const Block own(b.Block(i, k), width);
    // AddRows' sums (four rows a pass), over the rows' blocks of k.
    const auto add_rows = [&](const int* rows, int count, double scale) {
      AddInFours([&](int c) { return Block(b.Block(rows[c], k), width); },
                 count, scale, o);
    };
    const auto direct = [&] {
      o = r.self * own;
      add_rows(r.nb->data(), static_cast<int>(r.nb->size()), r.off);
    };
    if (!IsDenseUniform(r, n_, counted_[i])) {
      direct();
      return;
    }
    o = r.off * (sum - own) + r.self * own;
    if (static_cast<int>(r.nb->size()) == n_counted_ - 1) return;
    // A special row (a standard one has every other counted row).
    const std::vector<int>& left_out =
        left_out_[std::lower_bound(special_.begin(), special_.end(), i) -
                  special_.begin()];
    add_rows(left_out.data(), static_cast<int>(left_out.size()), -r.off);
    const int d = b.layout().dim(k);
    for (int e = 0; e < d; ++e) {
      const int diagonal = e * d + e;
      if (!(o[diagonal] > kCancelled * r.off * sum[diagonal])) {
        direct();  // ResumCancelledBlocks
        return;
      }
    }
  }

  void MixTarget(const BeliefSet& b, int k, BeliefSet* out, Scratch* s) const {
    const BeliefLayout& layout = b.layout();
    const int d = layout.dim(k), width = d * d + d;
    s->sum.resize(width);
    s->o.resize(width);
    // The rows mixed one by one: b's own rows of k and the special rows.
    s->rows.clear();
    if (b.sharing()) {
      const std::vector<int>& own = b.OwnRows(k);
      std::set_union(own.begin(), own.end(), special_.begin(), special_.end(),
                     std::back_inserter(s->rows));
      Sum(b, k, own, width, &s->sum);
    } else {
      for (int i = 0; i < n_; ++i) s->rows.push_back(i);
      Sum(b, k, s->rows, width, &s->sum);
    }
    // The common block's result, where some row of b holds it.
    double* common = out->CommonBlockToWrite(k);
    bool has_common =
        b.sharing() && b.OwnRows(k).size() < static_cast<std::size_t>(n_);
    if (has_common && has_standard_) {
      const Block c(b.CommonBlock(k), width);
      Eigen::Map<Eigen::ArrayXd>(common, width) =
          off_ * (s->sum - c) + self_ * c;
    } else {
      has_common = false;
    }
    s->own.clear();
    for (int i : s->rows) {
      MixRow(b, k, i, s->sum, &s->o);
      if (!has_common && !is_special_[i]) {
        std::copy_n(s->o.data(), width, common);
        has_common = true;
        continue;
      }
      if (has_common &&
          std::memcmp(s->o.data(), common, sizeof(double) * width) == 0)
        continue;
      std::copy_n(s->o.data(), width, out->RawBlock(i, k));
      s->own.push_back(i);
    }
    if (!has_common) {
      // No row holds a common result: every row was mixed one by one (the
      // special rows are all of them), and the common block is unused.
      std::fill_n(common, width, 0.0);
    }
    out->SetOwnRows(k, s->own);
  }

  int n_ = 0, n_counted_ = 0;
  const std::vector<RowWeights>* w_ = nullptr;
  bool has_standard_ = false;
  double self_ = 0.0, off_ = 0.0;
  std::vector<std::uint8_t> counted_, is_special_;
  std::vector<int> counted_before_, special_;
  std::vector<std::vector<int>> left_out_;  // per special row
};

void FuseRows(const BeliefSet& predicted, const std::vector<RowWeights>& w,
              const std::vector<std::vector<Measurement>>& z,
              const std::vector<Vec2>& positions, BeliefSet* out,
              const RangeRunner& run,
              const std::function<void(int row)>& row_done) {
  AIA_CHECK(out != &predicted);
  const int n = predicted.rows();
  AIA_CHECK(static_cast<int>(w.size()) == n);
  AIA_CHECK(static_cast<int>(z.size()) == n &&
            static_cast<int>(positions.size()) == n);
  if (out->rows() != n || &out->layout() != &predicted.layout()) {
    *out = BeliefSet(&predicted.layout(), n);
  }
  thread_local SharedMix shared;
  if (shared.Plan(w, n) && shared.Pays(predicted)) {
    const RangeRunner& split = SplitFor(n, predicted.layout().stride(), run);
    shared.Mix(predicted, out, split);
    for (int i = 0; i < n; ++i)
      if (!z[i].empty()) AddMeasurements(z[i], positions[i], out, i);
    return;
  }
  // Row by row over the storage: every block its own.
  const BeliefSet* from = &predicted;
  thread_local BeliefSet unshared;
  if (predicted.sharing()) {
    unshared = predicted;
    unshared.Unshare();
    from = &unshared;
  }
  out->Unshare();
  thread_local Eigen::ArrayXd sum;
  MixRows(predicted.layout(), w, from->data(), &out->data(), &sum, run,
          [&](int i) {
            AddMeasurements(z[i], positions[i], out, i);
            if (row_done) row_done(i);
          });
}

template <int D>
bool BlockSpd(const double* block, double tol) {
  const Eigen::Map<const MatD<D>> omega(block);
  if (!omega.allFinite()) return false;
  const double scale = omega.cwiseAbs().maxCoeff();
  if ((omega - omega.transpose()).cwiseAbs().maxCoeff() > tol * scale)
    return false;
  const Eigen::LLT<MatD<D>> llt(omega);
  return llt.info() == Eigen::Success;
}

}  // namespace

namespace {

// One block's time update, as Predict makes it: whether it was scaled back
// (PredictBlock), or the divergence's message in `failure`.
bool PredictOne(const BeliefLayout& layout, int k, double* block,
                std::string* failure) {
  try {
    return layout.dim(k) == 2 ? PredictBlock<2>(layout.model(k), block, true)
                              : PredictBlock<4>(layout.model(k), block, true);
  } catch (const EstimateDiverged& e) {
    *failure = e.what();
    return false;
  }
}

[[noreturn]] void ThrowDivergedEverywhere(int k) {
  throw EstimateDiverged(k, "its predicted variance passes " +
                                FormatNumber(kMaxVariance) +
                                " m^2, or its mean " + FormatNumber(kMaxMean) +
                                ", in every estimate that counts");
}

// Predict on a shared set: each target's common block once (where a row
// holds it) and its own blocks, targets split over `run`; the same blocks,
// failure and divergence as row by row (the common block's failure is the
// first row's that holds it).
void PredictShared(BeliefSet* beliefs, const std::vector<std::uint8_t>* active,
                   const RangeRunner& run) {
  const BeliefLayout& layout = beliefs->layout();
  const int rows = beliefs->rows(), m = layout.num_targets();
  const auto counts = [&](int r) { return active == nullptr || (*active)[r]; };
  // (Kept from call to call: no allocation a step.)
  thread_local std::vector<std::size_t> failure_at_storage;
  thread_local std::vector<std::string> failure_storage;
  thread_local std::vector<std::uint8_t> diverged_storage;
  std::vector<std::size_t>& failure_at = failure_at_storage;
  std::vector<std::string>& failure = failure_storage;
  std::vector<std::uint8_t>& diverged = diverged_storage;
  failure_at.assign(m, SIZE_MAX);
  failure.resize(m);
  diverged.assign(m, 0);
  RunRange(run, m, [&](int k0, int k1, int) {
    for (int k = k0; k < k1; ++k) {
      if (layout.is_static(k)) continue;
      const std::vector<int>& own = beliefs->OwnRows(k);
      // The first row holding the common block, and whether an active one
      // does.
      int first_shared = -1;
      bool active_shared = false;
      for (int r = 0, o = 0; r < rows; ++r) {
        if (o < static_cast<int>(own.size()) && own[o] == r) {
          ++o;
          continue;
        }
        if (first_shared < 0) first_shared = r;
        active_shared = counts(r);
        if (active_shared) break;
        // (Rows past the first inactive ones: a walk as long as the
        // failed robots' run, not the team.)
      }
      bool counted = false, kept = false;
      std::string message;
      const auto note = [&](int r, bool scaled, bool ok) {
        if (!ok) {
          const std::size_t at = static_cast<std::size_t>(r) * m + k;
          if (at < failure_at[k]) {
            failure_at[k] = at;
            failure[k] = message;
          }
        }
        return scaled;
      };
      if (first_shared >= 0) {
        message.clear();
        const bool scaled =
            PredictOne(layout, k, beliefs->CommonBlockToWrite(k), &message);
        note(first_shared, scaled, message.empty());
        if (active_shared) {
          counted = true;
          kept = kept || !scaled;
        }
      }
      for (int r : own) {
        message.clear();
        const bool scaled =
            PredictOne(layout, k, beliefs->RawBlock(r, k), &message);
        note(r, scaled, message.empty());
        if (counts(r)) {
          counted = true;
          kept = kept || !scaled;
        }
      }
      diverged[k] = counted && !kept;
    }
  });
  std::size_t first = SIZE_MAX;
  int at_k = -1;
  for (int k = 0; k < m; ++k)
    if (failure_at[k] < first) {
      first = failure_at[k];
      at_k = k;
    }
  if (at_k >= 0) throw EstimateDiverged(at_k, failure[at_k]);
  for (int k = 0; k < m; ++k)
    if (diverged[k]) ThrowDivergedEverywhere(k);
}

}  // namespace

void Predict(BeliefSet* beliefs, const std::vector<std::uint8_t>* active,
             const RangeRunner& run) {
  const BeliefLayout& layout = beliefs->layout();
  if (layout.all_static()) return;
  AIA_CHECK(active == nullptr ||
            static_cast<int>(active->size()) == beliefs->rows());
  if (beliefs->sharing()) {
    PredictShared(beliefs, active,
                  SplitFor(beliefs->rows(), layout.stride(), run));
    return;
  }
  BeliefSet::Storage& data = beliefs->data();
  const int rows = beliefs->rows(), m = layout.num_targets();
  // Per row and target: whether the prediction was scaled back. A row is
  // predicted whole on one thread; the first failure in row-major order is
  // the one thrown, whatever the split (a part stops at its own first).
  // (A lambda names this thread's thread_local, not the caller's: the
  // workers reach the vector through the reference.)
  thread_local std::vector<std::uint8_t> scaled_storage;
  std::vector<std::uint8_t>& scaled = scaled_storage;
  scaled.assign(static_cast<std::size_t>(rows) * m, 0);
  std::mutex failure_mutex;
  std::size_t failure_at = scaled.size();
  std::string failure;
  const RangeRunner& split = SplitFor(rows, data.cols(), run);
  RunRange(split, rows, [&](int r0, int r1, int) {
    for (int r = r0; r < r1; ++r) {
      double* row = data.data() + r * data.cols();
      for (int k = 0; k < m; ++k) {
        if (layout.is_static(k)) continue;
        double* block = row + layout.omega_offset(k);
        const std::size_t at = static_cast<std::size_t>(r) * m + k;
        try {
          scaled[at] = layout.dim(k) == 2
                           ? PredictBlock<2>(layout.model(k), block, true)
                           : PredictBlock<4>(layout.model(k), block, true);
        } catch (const EstimateDiverged& e) {
          const std::lock_guard<std::mutex> lock(failure_mutex);
          if (at < failure_at) {
            failure_at = at;
            failure = e.what();
          }
          return;
        }
      }
    }
  });
  if (failure_at < scaled.size())
    throw EstimateDiverged(static_cast<int>(failure_at % m), failure);
  // A target diverges when every row that counts was scaled back.
  for (int k = 0; k < m; ++k) {
    if (layout.is_static(k)) continue;
    bool counted = false, kept = false;
    for (int r = 0; r < rows && !kept; ++r) {
      if (active != nullptr && (*active)[r] == 0) continue;
      counted = true;
      kept = scaled[static_cast<std::size_t>(r) * m + k] == 0;
    }
    if (counted && !kept) ThrowDivergedEverywhere(k);
  }
}

void PredictInformationBlock(const TargetModel& model, double* block) {
  if (model.dim() == 2) {
    PredictBlock<2>(model, block, false);
  } else {
    PredictBlock<4>(model, block, false);
  }
}

void PredictInformationMatrix(const TargetModel& model, double* omega) {
  if (model.dim() == 2) {
    Eigen::Map<MatD<2>> m(omega);
    PredictOmega<2>(model, internal::InverseSpd<2>(m), m);
  } else {
    Eigen::Map<MatD<4>> m(omega);
    PredictOmega<4>(model, internal::InverseSpd<4>(m), m);
  }
}

void AddMeasurements(const std::vector<Measurement>& z, const Vec2& p,
                     BeliefSet* beliefs, int row) {
  const BeliefLayout& layout = beliefs->layout();
  AIA_CHECK(row >= 0 && row < beliefs->rows());
  for (const Measurement& m : z) {
    AIA_CHECK(m.target >= 0 && m.target < layout.num_targets());
    AIA_CHECK(m.precision >= 0.0);
    const int d = layout.dim(m.target);
    // Z = M' R^-1 M with M = [I 0], R^-1 = r I: r on the first two diagonal
    // entries of the column-major block.
    double* omega = beliefs->OwnBlock(row, m.target);
    omega[0] += m.precision;
    omega[d + 1] += m.precision;
    // M' R^-1 (y + p): y is relative to the robot, and y + p = M x + v is
    // the measurement of the target's absolute position.
    double* xi = omega + d * d;
    xi[0] += m.precision * (m.y.x() + p.x());
    xi[1] += m.precision * (m.y.y() + p.y());
  }
}

void FusionWeights(const std::vector<std::vector<int>>& neighbors,
                   double kappa_self, Eigen::MatrixXd* W) {
  const int n = static_cast<int>(neighbors.size());
  if (W->rows() != n || W->cols() != n) W->resize(n, n);
  W->setZero();
  for (int i = 0; i < n; ++i) {
    const std::vector<int>& ni = neighbors[i];
    if (ni.empty()) {
      (*W)(i, i) = 1.0;
      continue;
    }
    (*W)(i, i) = kappa_self;
    const double kappa_ij = (1.0 - kappa_self) / static_cast<double>(ni.size());
    for (const int j : ni) {
      AIA_CHECK_MSG(j >= 0 && j < n && j != i, "bad neighbour index");
      (*W)(i, j) = kappa_ij;
    }
  }
}

void MakeDkfWeights(const std::vector<std::vector<int>>& neighbors,
                    double kappa_self, DkfWeights* w) {
  const int n = static_cast<int>(neighbors.size());
  w->neighbors = &neighbors;
  w->self.resize(n);
  w->off.resize(n);
  for (int i = 0; i < n; ++i) {
    const std::vector<int>& ni = neighbors[i];
    if (ni.empty()) {
      w->self[i] = 1.0;
      w->off[i] = 0.0;
      continue;
    }
    w->self[i] = kappa_self;
    w->off[i] = (1.0 - kappa_self) / static_cast<double>(ni.size());
    for (std::size_t c = 0; c < ni.size(); ++c)
      AIA_CHECK_MSG(ni[c] >= 0 && ni[c] < n && ni[c] != i &&
                        (c == 0 || ni[c - 1] < ni[c]),
                    "neighbours must be distinct, ascending and not self");
  }
}

void Fuse(const BeliefSet& predicted, const DkfWeights& w,
          const std::vector<std::vector<Measurement>>& z,
          const std::vector<Vec2>& positions, BeliefSet* out,
          const RangeRunner& run,
          const std::function<void(int row)>& row_done) {
  const int n = predicted.rows();
  AIA_CHECK(w.neighbors != nullptr &&
            static_cast<int>(w.neighbors->size()) == n &&
            static_cast<int>(w.self.size()) == n &&
            static_cast<int>(w.off.size()) == n);
  thread_local std::vector<RowWeights> rows;
  rows.resize(n);
  for (int i = 0; i < n; ++i) {
    RowWeights& r = rows[i];
    r.uniform = true;
    r.self = w.self[i];
    r.off = w.off[i];
    r.nb = &(*w.neighbors)[i];
  }
  FuseRows(predicted, rows, z, positions, out, run, row_done);
}

void Fuse(const BeliefSet& predicted, const Eigen::MatrixXd& W,
          const std::vector<std::vector<Measurement>>& z,
          const std::vector<Vec2>& positions, BeliefSet* out) {
  const int n = predicted.rows();
  AIA_CHECK(W.rows() == n && W.cols() == n);
  // Each row as a uniform one where its off-diagonal weights are equal.
  std::vector<std::vector<int>> nb(n);
  std::vector<RowWeights> rows(n);
  for (int i = 0; i < n; ++i) {
    RowWeights& r = rows[i];
    r.self = W(i, i);
    for (int j = 0; j < n; ++j) {
      const double v = W(i, j);
      if (j == i || v == 0.0) continue;
      if (nb[i].empty()) {
        r.off = v;
      } else if (v != r.off) {
        r.uniform = false;
      }
      nb[i].push_back(j);
    }
    r.nb = &nb[i];
    r.dense = W.data() + i;  // column-major: W(i, j) at i + j * rows
    r.stride = W.rows();
  }
  FuseRows(predicted, rows, z, positions, out, {}, {});
}

void CentralUpdate(const std::vector<std::vector<Measurement>>& z,
                   const std::vector<Vec2>& positions, BeliefSet* central) {
  AIA_CHECK(central->rows() == 1);
  AIA_CHECK(z.size() == positions.size());
  for (size_t i = 0; i < z.size(); ++i)
    AddMeasurements(z[i], positions[i], central, 0);
}

bool AllBlocksSpd(const BeliefSet& beliefs, double tol) {
  const BeliefLayout& layout = beliefs.layout();
  for (int r = 0; r < beliefs.rows(); ++r) {
    for (int k = 0; k < layout.num_targets(); ++k) {
      const double* block = beliefs.Block(r, k);
      const bool ok = layout.dim(k) == 2 ? BlockSpd<2>(block, tol)
                                         : BlockSpd<4>(block, tol);
      if (!ok) return false;
    }
  }
  return true;
}

}  // namespace aia
