#include "aia/learning/scorer.h"

#include <algorithm>
#include <limits>

#include "aia/core/check.h"

namespace aia {

NetworkScorer::NetworkScorer(std::shared_ptr<const IgbNet> net,
                             Precision precision)
    : net_(std::move(net)), precision_(precision) {
  AIA_CHECK(net_ != nullptr);
}

void NetworkScorer::Reset(const Map& map, int num_robots, int num_targets) {
  bf16_ = UsesBFloat16(precision_, num_robots);
  renderer_.emplace(
      map.occupancy(), map.size(),
      AtLatticeStep(net_->config().channels, map.lattice().step()),
      &map.lattice());
  // The threads' heat grids are the map's shape: made again for this one.
  worker_heat_.clear();
  heat_known_.Clear();
  // Only a model that reads search points keeps them (N x M slots).
  if (net_->config().channels.search)
    search_.Reset(num_robots, num_targets);
  else
    search_.Reset(0, 0);
}

// What the steps of one Score call share: the call's arguments and what its
// first steps work out from them.
struct NetworkScorer::Step {
  const DecisionContext& ctx;
  const ScoringRows& team;
  const ScorerView& view;
  std::size_t size = 0;  // floats per image
  // Message passing: every row's features are needed, as the neighbours'
  // input.
  bool passing = false;
  // The view's unread rows are neither rendered nor scored.
  bool skipping = false;
  // The centred frame: the heat channel is folded from heat_.base().
  bool folding = false;
  const std::vector<double>* prior = nullptr;
  // Where each robot aims in the reach channel (null: the means).
  const SearchMemory* aims = nullptr;

  const std::vector<int>& rows() const { return team.rows; }
  bool Unread(int b) const { return skipping && (*view.unread)[b]; }
  // The targets row b is shown (empty: every target).
  const std::vector<std::uint8_t>& Shown(int b) const {
    static const std::vector<std::uint8_t> kAll;
    return view.shown && b < static_cast<int>(view.shown->size())
               ? (*view.shown)[b]
               : kAll;
  }
};

void NetworkScorer::Score(const DecisionContext& ctx, const ScoringRows& team,
                          const ScorerView& view, float* logits) {
  AIA_CHECK_MSG(renderer_.has_value(), "Reset() before Score()");
  MatchSensorRange(ctx);
  Step step{ctx, team, view};
  step.size = renderer_->ImageSize();
  step.passing = net_->config().message_hops > 0;
  ChooseRows(&step);
  const int workers = std::max(1, PolicyThreads());
  PrepareInputs(&step, workers);
  RenderAndRun(step);
  if (step.passing)
    PassMessages(step, logits);
  else
    WriteLogits(step, logits);
}

// Observation pixels within the sensor's range (AtSensorRange), known from
// the first context that has the sensor: the renderer is made again then.
void NetworkScorer::MatchSensorRange(const DecisionContext& ctx) {
  if (!ctx.sensor) return;
  const ChannelParams at_sensor = AtSensorRange(
      AtLatticeStep(net_->config().channels, ctx.map->lattice().step()),
      ctx.sensor->range);
  if (at_sensor.observe_range != renderer_->params().observe_range) {
    renderer_.emplace(ctx.map->occupancy(), ctx.map->size(), at_sensor,
                      &ctx.map->lattice());
    heat_known_.Clear();
  }
}

void NetworkScorer::ChooseRows(Step* step) {
  const ScorerView& view = step->view;
  const std::vector<int>& rows = step->rows();
  // With asynchronous decisions only the robots that decide are rendered
  // and scored, and of those only the ones whose logits are read (the
  // view's unread rows are skipped inside their chunk, RenderAndRun):
  // without messages a robot's logits are its own image's (the others' stay
  // 0); with messages every robot's features are needed.
  step->skipping = !step->passing && view.unread && !view.unread->empty() &&
                   std::find(view.unread->begin(), view.unread->end(), 1) !=
                       view.unread->end();
  AIA_CHECK(!view.unread || view.unread->empty() ||
            view.unread->size() == rows.size());
  order_.clear();
  for (int b = 0; b < static_cast<int>(rows.size()); ++b)
    if (step->passing || Deciding(step->ctx, rows[b])) order_.push_back(b);
  images_.resize(order_.size() * step->size);
}

void NetworkScorer::PrepareInputs(Step* step, int workers) {
  const DecisionContext& ctx = step->ctx;
  const std::vector<int>& rows = step->rows();
  step->prior = ctx.log_det_prior;
  if (!step->prior) {  // a hand-made context: every prior counts as det 1
    no_prior_.assign(ctx.beliefs->layout().num_targets(), 0.0);
    step->prior = &no_prior_;
  }
  // The team's heatmaps and the common one's fold (once for every robot
  // that holds it), kept while the team's knowledge and rows are the same.
  step->folding = renderer_->params().frame == ChannelFrame::kCentred;
  if (!heat_known_.Holds(ctx) || heat_rows_ != rows) {
    heat_.Prepare(*ctx.beliefs, rows, *step->prior, renderer_->Heatmap(ctx.eps),
                  renderer_->occupancy(), PolicyRunner(), workers);
    if (step->folding) fold_.Build(heat_.base());
    heat_known_.Set(ctx);
    heat_rows_ = rows;
  }
  if (static_cast<int>(worker_heat_.size()) < workers) {
    worker_heat_.resize(workers, renderer_->occupancy());
    worker_neighbours_.resize(workers);
    worker_targets_.resize(workers);
    worker_search_.resize(workers);
    worker_pair_.resize(workers);
    worker_edits_.resize(workers);
  }
  step->aims = renderer_->params().geodesic && !renderer_->params().search
                   ? step->view.aims
                   : nullptr;
  // The model's own search points (a hand-made context without a sensor, or
  // a team other than Reset's, has none this step: the means).
  searching_ =
      renderer_->params().search && ctx.sensor &&
      search_.num_robots() == static_cast<int>(ctx.robot_lattice->size()) &&
      search_.num_targets() == ctx.beliefs->layout().num_targets();
  if (searching_)  // the deciding robots' (see RulesLayer::Shape)
    RecordSearchPoints(ctx, rows, &search_, &deciding_, PolicyRunner(),
                       workers);
}

// Chunks of kForwardBatch robots: each rendered and run through the network
// by one thread (libtorch runs single-threaded inside), so that a robot's
// logits depend on its chunk, never on the number of threads. An unread row
// leaves its chunk's batch smaller: an image's logits are the same in a
// batch of any size from two on, so a robot left alone in its chunk goes as
// a batch of two copies (a chunk of one, as before, as one).
void NetworkScorer::RenderAndRun(const Step& step) {
  const int count = static_cast<int>(order_.size());
  const int chunks = (count + kForwardBatch - 1) / kForwardBatch;
  if (step.passing)
    features_.resize(step.rows().size() * net_->config().hidden);
  scored_.resize(order_.size() * kNumMoves);
  PrepareCallerTorchThreads(chunks);
  ParallelFor(chunks, 1, [&](int c0, int c1, int worker) {
    for (int c = c0; c < c1; ++c) {
      const int begin = c * kForwardBatch;
      const int end = std::min(count, begin + kForwardBatch);
      int made = 0;  // this chunk's images, packed from `begin` on
      for (int o = begin; o < end; ++o) {
        const int b = order_[o];
        if (step.Unread(b)) continue;
        RenderRow(step, b, images_.data() + (begin + made) * step.size, worker);
        ++made;
      }
      RunChunk(step, begin, end, made, worker);
      if (made != end - begin) UnpackChunk(step, begin, end, made);
    }
  });
}

void NetworkScorer::RenderRow(const Step& step, int b, float* image,
                              int worker) {
  const DecisionContext& ctx = step.ctx;
  const Lattice& lattice = ctx.map->lattice();
  const int i = step.rows()[b];
  const std::vector<std::uint8_t>& keep = step.Shown(b);
  std::vector<Vec2>& neighbours = worker_neighbours_[worker];
  neighbours.clear();
  for (int j : ctx.comm->Neighbors(i))
    if (j != i) neighbours.push_back(lattice.Point((*ctx.robot_lattice)[j]));
  std::vector<HeatSource>* targets = nullptr;
  if (renderer_->params().geodesic) {
    targets = &worker_targets_[worker];
    // The reach channel reads the means and log dets only, and a target
    // the robot is not shown (log det -inf) by neither.
    const int m = ctx.beliefs->layout().num_targets();
    targets->resize(m);
    for (int k = 0; k < m; ++k) {
      HeatSource& t = (*targets)[k];
      if (!keep.empty() && !keep[k]) {
        t.log_det = -std::numeric_limits<double>::infinity();
        continue;
      }
      t.mean = step.aims ? step.aims->Aim(i, k) : MeanOf(ctx, i, k);
      t.log_det = LogDetOf(ctx, i, k);
    }
  }
  RobotMemory memory;
  if (searching_) SetSearchPoints(search_, i, &worker_search_[worker], &memory);
  const int here = (*ctx.robot_lattice)[i];
  SetTrail(lattice, here, ctx.history ? ctx.history->last(i) : Move::kStay,
           &memory);
  // With the fold, a robot's own heatmap is never made: the base's fold
  // with its edits (HeatFold::FoldEdited).
  const bool folded = step.folding && keep.empty();
  std::vector<HeatEdit>& edits = worker_edits_[worker];
  edits.clear();
  if (folded) heat_.Edits(b, &edits);
  Grid<float>& heat = worker_heat_[worker];
  renderer_->RenderWithHeat(lattice.Point(here), neighbours,
                            folded
                                ? heat_.base()
                                : (keep.empty() ? heat_.Robot(b, &heat)
                                                : heat_.Robot(b, keep, &heat)),
                            targets, step.prior, ctx.eps, image, memory,
                            step.folding ? &fold_ : nullptr, &edits);
}

// The chunk [begin, end)'s `made` packed images through the network: their
// features (message passing) or their logits, packed into scored_ from
// `begin` on.
void NetworkScorer::RunChunk(const Step& step, int begin, int end, int made,
                             int worker) {
  const float* images = images_.data() + begin * step.size;
  float* scored = scored_.data() + begin * kNumMoves;
  if (step.passing) {
    const int hidden = net_->config().hidden;
    net_->Embed(images, end - begin, renderer_->height(), renderer_->width(),
                features_.data() + begin * hidden, bf16_);
  } else if (made == 1 && (step.ctx.ready || end - begin > 1)) {
    ForwardAlone(images, step.size, scored, worker);
  } else if (made > 0) {
    net_->Forward(images, made, renderer_->height(), renderer_->width(), scored,
                  bf16_);
  }
}

// The chunk's packed logits unpacked to its rows, from the last (a row's
// packed place is never after its own); an unread row's are 0.
void NetworkScorer::UnpackChunk(const Step& step, int begin, int end,
                                int made) {
  const float* scored = scored_.data() + begin * kNumMoves;
  for (int o = end - 1, j = made - 1; o >= begin; --o) {
    float* row = scored_.data() + o * kNumMoves;
    if (step.Unread(order_[o])) {
      std::fill_n(row, kNumMoves, 0.0f);
    } else {
      const float* packed = scored + j * kNumMoves;
      if (packed != row) std::copy_n(packed, kNumMoves, row);
      --j;
    }
  }
}

// Without messages: each scored row's logits in its place, the others' 0.
void NetworkScorer::WriteLogits(const Step& step, float* logits) const {
  const int count = static_cast<int>(order_.size());
  const std::vector<int>& rows = step.rows();
  if (count < static_cast<int>(rows.size()))
    std::fill_n(logits, rows.size() * kNumMoves, 0.0f);
  for (int o = 0; o < count; ++o)
    std::copy_n(scored_.data() + o * kNumMoves, kNumMoves,
                logits + order_[o] * kNumMoves);
}

// The team's features over this step's graph among the active robots.
void NetworkScorer::PassMessages(const Step& step, float* logits) {
  const std::vector<int>& rows = step.rows();
  const std::vector<int>& row_of = step.team.row_of;
  graph_.offsets.assign(1, 0);
  graph_.neighbours.clear();
  for (int b = 0; b < static_cast<int>(rows.size()); ++b) {
    for (int j : step.ctx.comm->Neighbors(rows[b]))
      if (j != rows[b] && row_of[j] >= 0)
        graph_.neighbours.push_back(row_of[j]);
    graph_.offsets.push_back(static_cast<int>(graph_.neighbours.size()));
  }
  net_->Head(features_.data(), graph_, logits);
}

void RecordSearchPoints(const DecisionContext& ctx,
                        const std::vector<int>& rows, SearchPoints* points,
                        std::vector<int>* deciding, const RangeRunner& run,
                        int workers) {
  DecidingRows(ctx, rows, deciding);
  // As the model's data were recorded (aia dataset): a belief that shrank
  // ends a search, so that its input is what it was trained on.
  DecisionContext recorded = ctx;
  recorded.measurements = nullptr;
  points->Update(recorded, *deciding, run, workers);
  points->Share(recorded, *deciding, run, workers);
}

void SetSearchPoints(const SearchPoints& points, int robot,
                     SearchPointSets* sets, RobotMemory* memory) {
  sets->resize(points.num_targets());
  for (int k = 0; k < points.num_targets(); ++k)
    (*sets)[k] = points.Points(robot, k);
  memory->search = sets;
}

// One image through the network as a batch of two copies: libtorch 1.13's
// CPU convolution takes a path about ten times slower per image for a batch
// of one, and asynchronous decisions often score one robot at a time. (The
// logits differ from a batch of one's in the 7th digit, so lockstep, which
// must repeat its runs byte for byte, keeps the batch of one.)
void NetworkScorer::ForwardAlone(const float* image, std::size_t size,
                                 float* logits, int worker) {
  std::vector<float>& pair = worker_pair_[worker];
  pair.resize(2 * size);
  std::copy_n(image, size, pair.data());
  std::copy_n(image, size, pair.data() + size);
  float two[2 * kNumMoves];
  net_->Forward(pair.data(), 2, renderer_->height(), renderer_->width(), two,
                bf16_);
  std::copy_n(two, kNumMoves, logits);
}

}  // namespace aia
