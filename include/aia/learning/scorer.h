// The igbnet policy's scorer (docs/learning.md, The igbnet policy): the
// network and its input, nothing else. For every active robot it renders the
// channels from what the robot knows (its own fused belief, its neighbours'
// points in this step's graph, the map) and writes the four moves' logits; it
// chooses no move. What the coordination layer's observation shapers change
// about that input (learning/coordination.h) comes in a ScorerView.
#ifndef AIA_LEARNING_SCORER_H_
#define AIA_LEARNING_SCORER_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "aia/learning/channels.h"
#include "aia/learning/network.h"
#include "aia/planning/policy.h"
#include "aia/planning/search.h"

namespace aia {

// This step's active robots: row b is robot rows[b]; row_of[i] is robot i's
// row (-1: inactive).
struct ScoringRows {
  std::vector<int> rows;
  std::vector<int> row_of;
  int size() const { return static_cast<int>(rows.size()); }
};

// What the observation shapers leave for the scorer.
struct ScorerView {
  // Per row: the targets whose heat and reach the robot is shown (an empty
  // entry: every target); null: every target for every row.
  const std::vector<std::vector<std::uint8_t>>* shown = nullptr;
  // Where each robot aims for each target in the reach channel; null: its
  // belief's means.
  const SearchMemory* aims = nullptr;
  // Per row: 1 where no part reads the row's logits this step (a robot the
  // rules' walk moves); such a row is neither rendered nor scored, and its
  // logits are 0, unless the model passes messages (its features are its
  // neighbours' input). Null or empty: every row is scored.
  const std::vector<std::uint8_t>* unread = nullptr;
};

class MoveScorer {
 public:
  virtual ~MoveScorer() = default;
  // A new episode on `map`.
  virtual void Reset(const Map& map, int num_robots, int num_targets) = 0;
  // The logits of every row's four moves (core/types.h order), row-major,
  // into logits[0, rows.size() * kNumMoves); a row the view marks unread
  // may be left at 0.
  virtual void Score(const DecisionContext& ctx, const ScoringRows& rows,
                     const ScorerView& view, float* logits) = 0;
  // Whether the input shows ScorerView::aims (a reach channel).
  virtual bool ShowsAims() const = 0;
  // Whether this episode's scores come from bfloat16 arithmetic
  // (learning/network.h, Precision).
  virtual bool BFloat16() const { return false; }
};

// One decision step of a model's own search points (ChannelParams::search),
// as the igbnet policy and `aia dataset` record them: the misses of the
// robots of `rows` that decide (into `deciding`), shared over this step's
// graph. The context's measurements are not read: a belief that shrank
// ends a search. Call it once for every decision step, in order.
void RecordSearchPoints(const DecisionContext& ctx,
                        const std::vector<int>& rows, SearchPoints* points,
                        std::vector<int>* deciding, const RangeRunner& run = {},
                        int workers = 1);

// Robot `robot`'s search points of every target, copied into `sets` (kept
// by the caller), as memory->search.
void SetSearchPoints(const SearchPoints& points, int robot,
                     SearchPointSets* sets, RobotMemory* memory);

// I-GBNet: the channels of learning/channels.h, one batched forward per
// chunk of robots (learning/network.h), message passing over this step's
// graph where the model has it.
class NetworkScorer : public MoveScorer {
 public:
  // `precision` is resolved for each episode's team at Reset.
  explicit NetworkScorer(std::shared_ptr<const IgbNet> net,
                         Precision precision = Precision::kFloat32);
  void Reset(const Map& map, int num_robots, int num_targets) override;
  void Score(const DecisionContext& ctx, const ScoringRows& rows,
             const ScorerView& view, float* logits) override;
  // A model that reads its own search points shows no aims of the view.
  bool ShowsAims() const override {
    return net_->config().channels.geodesic && !net_->config().channels.search;
  }
  bool BFloat16() const override { return bf16_; }
  // The search points of a model that reads them (empty before the first
  // step and for other models).
  const SearchPoints& search() const { return search_; }

 private:
  // Robots in one forward of the network.
  static constexpr int kForwardBatch = 32;
  // Score's steps, in order; what they share is a Step (scorer.cc).
  struct Step;
  void MatchSensorRange(const DecisionContext& ctx);
  // order_: the rows rendered and scored.
  void ChooseRows(Step* step);
  // The priors, heatmaps, fold, per-worker scratch and search points.
  void PrepareInputs(Step* step, int workers);
  // Every chunk of order_ rendered and run through the network.
  void RenderAndRun(const Step& step);
  // Row b's image into `image`.
  void RenderRow(const Step& step, int b, float* image, int worker);
  void RunChunk(const Step& step, int begin, int end, int made, int worker);
  void UnpackChunk(const Step& step, int begin, int end, int made);
  void WriteLogits(const Step& step, float* logits) const;
  void PassMessages(const Step& step, float* logits);
  std::shared_ptr<const IgbNet> net_;
  Precision precision_;
  bool bf16_ = false;  // precision_ for this episode's team
  std::optional<ChannelRenderer> renderer_;
  std::vector<float> images_;
  // The team rows rendered and scored (async: the deciding ones), and their
  // logits in that order.
  std::vector<int> order_, deciding_;
  std::vector<std::vector<float>> worker_pair_;      // ForwardAlone's batch
  std::vector<std::vector<HeatEdit>> worker_edits_;  // a robot's heat edits
  void ForwardAlone(const float* image, std::size_t size, float* logits,
                    int worker);
  std::vector<float> scored_;
  // Message passing (a model with message_hops > 0): the rows' hidden
  // features and their graph in row indices.
  std::vector<float> features_;
  TeamGraph graph_;
  TeamHeatmap heat_;
  HeatFold fold_;  // heat_.base()'s, for the centred frame
  // What heat_ and fold_ were made from: the knowledge and the rows.
  KnowledgeMark heat_known_;
  std::vector<int> heat_rows_;
  // Per worker thread (ParallelFor): a heatmap, the neighbours' points and
  // the targets of channel 4.
  std::vector<Grid<float>> worker_heat_;
  std::vector<std::vector<Vec2>> worker_neighbours_;
  std::vector<std::vector<HeatSource>> worker_targets_;
  std::vector<double> no_prior_;
  // A model whose reach channel reads search points (ChannelParams::search)
  // keeps each robot's, from its own and its neighbours' misses (part of its
  // input, whatever the coordination); per worker, one robot's copy.
  SearchPoints search_;
  bool searching_ = false;  // this step's search_ is the team's
  std::vector<SearchPointSets> worker_search_;
};

}  // namespace aia

#endif  // AIA_LEARNING_SCORER_H_
