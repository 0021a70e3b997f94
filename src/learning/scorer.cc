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
  // Only a model that reads search points keeps them (N x M slots).
  if (net_->config().channels.search)
    search_.Reset(num_robots, num_targets);
  else
    search_.Reset(0, 0);
}

void NetworkScorer::Score(const DecisionContext& ctx, const ScoringRows& team,
                          const ScorerView& view, float* logits) {
  AIA_CHECK_MSG(renderer_.has_value(), "Reset() before Score()");
  // Observation pixels within the sensor's range (AtSensorRange), known from
  // the first context that has the sensor: the renderer is made again then.
  if (ctx.sensor) {
    const ChannelParams at_sensor = AtSensorRange(
        AtLatticeStep(net_->config().channels, ctx.map->lattice().step()),
        ctx.sensor->range);
    if (at_sensor.observe_range != renderer_->params().observe_range)
      renderer_.emplace(ctx.map->occupancy(), ctx.map->size(), at_sensor,
                        &ctx.map->lattice());
  }
  const Lattice& lattice = ctx.map->lattice();
  const std::vector<int>& rows = team.rows;
  const std::size_t size = renderer_->ImageSize();
  const bool passing = net_->config().message_hops > 0;
  // With asynchronous decisions only the robots that decide are rendered
  // and scored, and of those only the ones whose logits are read (the
  // view's unread rows are skipped inside their chunk, below): without
  // messages a robot's logits are its own image's (the others' stay 0);
  // with messages every robot's features are needed.
  const bool skipping = !passing && view.unread && !view.unread->empty() &&
                        std::find(view.unread->begin(), view.unread->end(),
                                  1) != view.unread->end();
  AIA_CHECK(!view.unread || view.unread->empty() ||
            view.unread->size() == rows.size());
  const auto unread = [&](int b) { return skipping && (*view.unread)[b]; };
  order_.clear();
  for (int b = 0; b < static_cast<int>(rows.size()); ++b)
    if (passing || Deciding(ctx, rows[b])) order_.push_back(b);
  images_.resize(order_.size() * size);
  const std::vector<double>* prior = ctx.log_det_prior;
  if (!prior) {  // a hand-made context: every prior counts as det 1
    no_prior_.assign(ctx.beliefs->layout().num_targets(), 0.0);
    prior = &no_prior_;
  }
  const int workers = std::max(1, PolicyThreads());
  heat_.Prepare(*ctx.beliefs, rows, *prior, renderer_->Heatmap(ctx.eps),
                renderer_->occupancy(), PolicyRunner(), workers);
  // The common heatmap's fold, once for every robot that holds it.
  const bool folding = renderer_->params().frame == ChannelFrame::kCentred;
  if (folding) fold_.Build(heat_.base());
  if (static_cast<int>(worker_heat_.size()) < workers) {
    worker_heat_.resize(workers, renderer_->occupancy());
    worker_neighbours_.resize(workers);
    worker_targets_.resize(workers);
    worker_search_.resize(workers);
    worker_pair_.resize(workers);
    worker_edits_.resize(workers);
  }
  const bool geodesic = renderer_->params().geodesic;
  const SearchMemory* aims =
      geodesic && !renderer_->params().search ? view.aims : nullptr;
  // The model's own search points (a hand-made context without a sensor, or
  // a team other than Reset's, has none this step: the means).
  searching_ =
      renderer_->params().search && ctx.sensor &&
      search_.num_robots() == static_cast<int>(ctx.robot_lattice->size()) &&
      search_.num_targets() == ctx.beliefs->layout().num_targets();
  if (searching_)  // the deciding robots' (see RulesLayer::Shape)
    RecordSearchPoints(ctx, rows, &search_, &deciding_, PolicyRunner(),
                       workers);
  static const std::vector<std::uint8_t> kAll;
  auto shown = [&](int b) -> const std::vector<std::uint8_t>& {
    return view.shown && b < static_cast<int>(view.shown->size())
               ? (*view.shown)[b]
               : kAll;
  };
  // Chunks of kForwardBatch robots: each rendered and run through the
  // network by one thread (libtorch runs single-threaded inside), so that a
  // robot's logits depend on its chunk, never on the number of threads. An
  // unread row leaves its chunk's batch smaller: an image's logits are the
  // same in a batch of any size from two on, so a robot left alone in its
  // chunk goes as a batch of two copies (a chunk of one, as before, as one).
  const int count = static_cast<int>(order_.size());
  const int chunks = (count + kForwardBatch - 1) / kForwardBatch;
  const int hidden = net_->config().hidden;
  if (passing) features_.resize(rows.size() * hidden);
  scored_.resize(order_.size() * kNumMoves);
  ParallelFor(chunks, 1, [&](int c0, int c1, int worker) {
    Grid<float>& heat = worker_heat_[worker];
    std::vector<Vec2>& neighbours = worker_neighbours_[worker];
    for (int c = c0; c < c1; ++c) {
      const int begin = c * kForwardBatch;
      const int end = std::min(count, begin + kForwardBatch);
      int made = 0;  // this chunk's images, packed from `begin` on
      for (int o = begin; o < end; ++o) {
        const int b = order_[o];
        if (unread(b)) continue;
        const int i = rows[b];
        const std::vector<std::uint8_t>& keep = shown(b);
        neighbours.clear();
        for (int j : ctx.comm->Neighbors(i))
          if (j != i)
            neighbours.push_back(lattice.Point((*ctx.robot_lattice)[j]));
        std::vector<HeatSource>* targets = nullptr;
        if (geodesic) {
          targets = &worker_targets_[worker];
          // The reach channel reads the means and log dets only, and a
          // target the robot is not shown (log det -inf) by neither.
          const int m = ctx.beliefs->layout().num_targets();
          targets->resize(m);
          for (int k = 0; k < m; ++k) {
            HeatSource& t = (*targets)[k];
            if (!keep.empty() && !keep[k]) {
              t.log_det = -std::numeric_limits<double>::infinity();
              continue;
            }
            t.mean = aims ? aims->Aim(i, k) : MeanOf(ctx, i, k);
            t.log_det = LogDetOf(ctx, i, k);
          }
        }
        RobotMemory memory;
        if (searching_)
          SetSearchPoints(search_, i, &worker_search_[worker], &memory);
        const int here = (*ctx.robot_lattice)[i];
        SetTrail(lattice, here,
                 ctx.history ? ctx.history->last(i) : Move::kStay, &memory);
        // With the fold, a robot's own heatmap is never made: the base's
        // fold with its edits (HeatFold::FoldEdited).
        std::vector<HeatEdit>& edits = worker_edits_[worker];
        edits.clear();
        if (folding && keep.empty()) heat_.Edits(b, &edits);
        renderer_->RenderWithHeat(
            lattice.Point(here), neighbours,
            folding && keep.empty()
                ? heat_.base()
                : (keep.empty() ? heat_.Robot(b, &heat)
                                : heat_.Robot(b, keep, &heat)),
            targets, prior, ctx.eps, images_.data() + (begin + made) * size,
            memory, folding ? &fold_ : nullptr, &edits);
        ++made;
      }
      float* scored = scored_.data() + begin * kNumMoves;
      if (passing)
        net_->Embed(images_.data() + begin * size, end - begin,
                    renderer_->height(), renderer_->width(),
                    features_.data() + begin * hidden, bf16_);
      else if (made == 1 && (ctx.ready || end - begin > 1))
        ForwardAlone(images_.data() + begin * size, size, scored, worker);
      else if (made > 0)
        net_->Forward(images_.data() + begin * size, made, renderer_->height(),
                      renderer_->width(), scored, bf16_);
      if (made == end - begin) continue;
      // Unpacked to the chunk's rows, from the last (a row's packed place is
      // never after its own).
      for (int o = end - 1, j = made - 1; o >= begin; --o) {
        float* row = scored_.data() + o * kNumMoves;
        if (unread(order_[o])) {
          std::fill_n(row, kNumMoves, 0.0f);
        } else {
          const float* packed = scored + j * kNumMoves;
          if (packed != row) std::copy_n(packed, kNumMoves, row);
          --j;
        }
      }
    }
  });
  if (!passing) {
    if (count < static_cast<int>(rows.size()))
      std::fill_n(logits, rows.size() * kNumMoves, 0.0f);
    for (int o = 0; o < count; ++o)
      std::copy_n(scored_.data() + o * kNumMoves, kNumMoves,
                  logits + order_[o] * kNumMoves);
    return;
  }
  const int count_all = static_cast<int>(rows.size());
  // The team's features over this step's graph among the active robots.
  graph_.offsets.assign(1, 0);
  graph_.neighbours.clear();
  for (int b = 0; b < count_all; ++b) {
    for (int j : ctx.comm->Neighbors(rows[b]))
      if (j != rows[b] && team.row_of[j] >= 0)
        graph_.neighbours.push_back(team.row_of[j]);
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
