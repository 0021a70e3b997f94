// I-GBNet's input (docs/learning.md, Channels): per robot, four images over
// the workspace and up to four optional ones (4 reach, then trail, broad
// reach and second reach), one definition shared by the dataset reader, the
// trainer, the igbnet policy (Python reads the states: tools/igbnet.py). No
// torch here.
//   0 occupancy: the share of the pixel covered by obstacles (1 outside the
//     workspace);
//   1 own position: 1 at the robot's pixel;
//   2 neighbours: the number of this step's neighbours (self excluded) in
//     each pixel, at most ChannelParams::neighbour_cap where that is set;
//   3 heat: the robot's own fused belief projected as the heatmap of
//     estimation/heatmap.h;
//   4 reach (ChannelParams::geodesic, off in the paper's networks): where
//     the robot could measure each unlocalized target of its belief, carried
//     along free space. A target's observation pixels are the free pixels
//     within `observe_range` of its mean that see the mean (no occupied cell
//     of the map on the segment); each holds the target's heat weight w_k.
//     G(p) = max over observation pixels q of w(q) exp(-d(p, q) / L), d the
//     number of valid lattice moves inside the image (so walls and doors
//     shape it); observation pixels beyond the window count at the window's
//     border with the moves beyond it; 0 where a robot cannot stand; divided
//     by its largest value in the image. ChannelParams' reach_world and
//     search change where it is computed and from which sources;
//   then, each when on: trail (ChannelParams::trail), 1 at the pixel the
//     robot came from; broad reach (reach_broad); second reach
//     (reach_second).
// Two frames. Global (the paper's): the whole workspace, pixel (ix, iy)
// covering [ix, ix + 1) x [iy, iy + 1) cells of `cell` metres. Centred: a
// window of `window` x `window` pixels of the same global pixel grid, the
// robot's pixel at (window / 2, window / 2); pixels outside the workspace
// are occupied, and the heat of pixels beyond the window is folded onto the
// window's border (each border pixel holds the largest heat beyond it in
// its direction, so that work out of sight still points the way;
// neighbours beyond the window are counted on the border the same way).
#ifndef AIA_LEARNING_CHANNELS_H_
#define AIA_LEARNING_CHANNELS_H_

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "aia/core/fields.h"
#include "aia/core/grid.h"
#include "aia/core/types.h"
#include "aia/estimation/heatmap.h"
#include "aia/world/lattice.h"

namespace aia {

// Channels of the paper's network (ChannelParams::num_channels() adds the
// optional ones).
inline constexpr int kNumChannels = 4;

enum class ChannelFrame { kGlobal = 0, kCentred = 1 };
// Read by name ("centered" too); written as the first name of the value.
constexpr std::array<EnumName<ChannelFrame>, 3> EnumNames(ChannelFrame) {
  return {{{ChannelFrame::kGlobal, "global"},
           {ChannelFrame::kCentred, "centred"},
           {ChannelFrame::kCentred, "centered"}}};
}

struct ChannelParams {
  ChannelFrame frame = ChannelFrame::kCentred;
  double cell = 0.5;             // metres per pixel
  int window = 40;               // centred frame: pixels per side
  double blur = 1.0;             // the heatmap's s, metres
  double cutoff = 4.0;           // the heatmap's cut-off, standard deviations
  bool geodesic = false;         // channel 4, reach
  double geodesic_length = 5.0;  // its L, metres
  double observe_range = 2.0;    // its observation pixels' range, metres
  // Centred frame: channel 4 is computed over the window and this many
  // pixels around it, then cropped (0: the window alone).
  int reach_margin = 0;
  // Channel 4 over the whole workspace (distances along free space to every
  // observation pixel, however far), in log space so that no way fades out,
  // cropped to the window and scaled at the robot's own pixel: it holds
  // exp(-2), a pixel whose way is d moves shorter exp(d cell / L - 2),
  // capped at 1 (the way on from where the robot stands reads the same
  // whatever the distance to the goal).
  bool reach_world = false;
  // With reach_world: channel 4's sources are the observation pixels of each
  // unlocalized target's search points (planning/search.h, SearchPoints:
  // where the robot's and its neighbours' misses leave the target), not of
  // its mean alone.
  bool search = false;
  // With reach_world, above 0: channel 4 as the robot sees it from where it
  // stands. A window pixel p keeps its value times exp(-(m(p) - |p - r|_1)
  // cell / reach_detour), m(p) the number of valid moves from the robot's
  // pixel r to p inside the window and |p - r|_1 the fewest any lattice
  // allows: a way the robot can take straight on keeps its brightness, the
  // far side of a wall (nearer the goal, but a detour away) goes dark, and
  // a pixel the robot cannot reach inside the window reads 0. In metres
  // (0: off).
  double reach_detour = 0.0;
  // A last channel, trail: the pixel of the lattice point the robot came
  // from (its last lattice move; none before its first) holds 1.
  bool trail = false;
  // With reach_world, above 0: a last channel (after the trail), broad
  // reach: channel 4 again, from the same sources, at decay length
  // reach_broad metres and without the detour, so that the way to a
  // target other than the nearest still shows (at a short L the branch
  // toward a farther target reads like any step off the way). In metres
  // (0: off).
  double reach_broad = 0.0;
  // With reach_world: a last channel (after the trail and the broad reach),
  // second reach: channel 4 from each pixel's second target, the least cost
  // over the sources of every target but the one of least cost there (same
  // L, same detour). Where the ways to two targets part, the branch toward
  // the farther one leads on here, however far it is, up to the pixels
  // nearer that target, where channel 4 leads on to it.
  bool reach_second = false;
  // Above 0: the neighbours channel holds at most this many in a pixel. Its
  // border pixels count every neighbour beyond the window in their
  // direction, so their counts grow with the team (up to about 30 with the
  // 80 robots of the training data, hundreds at 500); a model trained on
  // small teams reads them at the cap (0: counts as they are).
  int neighbour_cap = 0;

  int num_channels() const {
    return kNumChannels + (geodesic ? 1 : 0) + (trail ? 1 : 0) +
           (reach_broad > 0.0 ? 1 : 0) + (reach_second ? 1 : 0);
  }
  // The index of the trail channel (when on), of the broad reach and of the
  // second reach.
  int trail_channel() const { return kNumChannels + (geodesic ? 1 : 0); }
  int broad_channel() const { return trail_channel() + (trail ? 1 : 0); }
  int second_channel() const {
    return broad_channel() + (reach_broad > 0.0 ? 1 : 0);
  }
  // The first setting given without the one it needs, as {setting, the one
  // it needs} (metadata keys), or {"", ""} when none: reach_world needs
  // geodesic; search, reach_detour, reach_broad and reach_second need
  // reach_world. The model's metadata, aia train's flags and Python's
  // channel settings are all refused by it.
  std::pair<std::string_view, std::string_view> MissingPrerequisite() const {
    if (reach_world && !geodesic) return {"reach_world", "geodesic"};
    if (search && !reach_world) return {"search", "reach_world"};
    if (reach_detour > 0.0 && !reach_world)
      return {"reach_detour", "reach_world"};
    if (reach_broad > 0.0 && !reach_world)
      return {"reach_broad", "reach_world"};
    if (reach_second && !reach_world) return {"reach_second", "reach_world"};
    return {"", ""};
  }
  // The channels' names in order: occupancy, own, neighbours, heat, then
  // those of reach, trail, broad and second that are on.
  std::vector<std::string> names() const {
    std::vector<std::string> n = {"occupancy", "own", "neighbours", "heat"};
    if (geodesic) n.push_back("reach");
    if (trail) n.push_back("trail");
    if (reach_broad > 0.0) n.push_back("broad");
    if (reach_second) n.push_back("second");
    return n;
  }

  // Declared once (core/fields.h) for the model file's metadata and for
  // `aia train`'s flags (each key is the flag with '-' for '_').
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(frame).Doc(
        "input frame: centred (a window around the robot) or global (the "
        "whole workspace)"));
    a->Visit(AIA_FIELD(cell).In(Between(0.05, 10.0)).Doc("metres per pixel"));
    a->Visit(AIA_FIELD(window)
                 .In(Between(4, 512))
                 .Doc("centred frame: pixels per side"));
    a->Visit(AIA_FIELD(blur)
                 .In(Between(0.0, 100.0))
                 .Doc("the heatmap's s in metres (about half the sensor "
                      "range)"));
    a->Visit(AIA_FIELD(cutoff)
                 .In({0.0, 100.0, true, false})
                 .Doc("the heatmap's cut-off, standard deviations"));
    a->Visit(AIA_FIELD(geodesic).Doc(
        "a fifth channel, reach: where each unlocalized target could be "
        "measured, carried along free space (docs/learning.md, Channels)"));
    a->Visit(AIA_FIELD(geodesic_length)
                 .In({0.0, 1000.0, true, false})
                 .Doc("the reach channel's decay length L in metres"));
    a->Visit(AIA_FIELD(observe_range)
                 .In({0.0, 100.0, true, false})
                 .Doc("the reach channel's observation range in metres"));
    a->Visit(AIA_FIELD(reach_margin)
                 .In(Between(0, 512))
                 .Doc("centred frame: pixels around the window the reach "
                      "channel is computed over before the crop"));
    a->Visit(
        AIA_FIELD(reach_world)
            .Doc("the reach channel over the whole workspace (the way to every "
                 "observation pixel along free space, however far), cropped to "
                 "the "
                 "window; reach_margin is then unused"));
    a->Visit(AIA_FIELD(search).Doc(
        "with reach_world: the reach channel leads to each target's search "
        "points (where the robot's and its neighbours' missed measurements "
        "leave it), not to its mean alone"));
    a->Visit(AIA_FIELD(reach_detour)
                 .In(Between(0.0, 1000.0))
                 .Doc("with reach_world: the reach channel dimmed by the "
                      "detour from the robot, exp(-detour / reach_detour) "
                      "with the detour in metres (moves inside the window "
                      "beyond the Manhattan distance); 0: off"));
    a->Visit(AIA_FIELD(trail).Doc(
        "a channel after reach, trail: the pixel the robot came from (its "
        "last lattice move) at 1"));
    a->Visit(AIA_FIELD(reach_broad)
                 .In(Between(0.0, 1000.0))
                 .Doc("with reach_world, above 0: a last channel, the reach "
                      "channel again at this decay length in metres and "
                      "without the detour (the ways to targets beyond the "
                      "nearest); 0: off"));
    a->Visit(AIA_FIELD(reach_second)
                 .Doc("with reach_world: a last channel, the reach channel "
                      "from each pixel's second target (the least cost over "
                      "every target but the one of least cost there), same "
                      "L and detour"));
    a->Visit(AIA_FIELD(neighbour_cap)
                 .In(Between(0, 1000000))
                 .Doc("above 0: the neighbours channel holds at most this "
                      "many in a pixel (its border pixels count every "
                      "neighbour beyond the window in their direction, "
                      "hundreds in large teams); 0: counts as they are"));
  }
};

// Channel 4's search points, per target (ChannelParams::search); an empty
// entry: the target's mean.
using SearchPointSets = std::vector<std::vector<Vec2>>;

// What a robot remembers, for the channels that show it: its search points
// (null: the means) and the point it came from (the trail channel; none
// before its first move).
struct RobotMemory {
  const SearchPointSets* search = nullptr;
  bool moved = false;
  Vec2 came_from{0.0, 0.0};
};

// The trail of a robot at lattice point `here` whose last applied move was
// `last` (kStay: none): the point it came from, into memory->moved and
// memory->came_from.
void SetTrail(const Lattice& lattice, int here, Move last, RobotMemory* memory);

// The heat channel's fold of one heatmap (the centred frame's border,
// above) for any window at once: running maxima along each row, down and
// up each column, and over the four corners of the map, made in O(cells),
// so that a window's fold reads O(window^2) of them instead of every cell
// of the map. Its values must be >= 0 (a heatmap's sums of stamps are);
// the fold is then exactly the fold of the heatmap itself (a max is a max).
class HeatFold {
 public:
  void Build(const Grid<float>& heat);
  // The heatmap it was built from (null before Build).
  const Grid<float>* heat() const { return heat_; }
  // Adds to the w x w plane `out` (row-major; pixel (0, 0) is map cell (x0,
  // y0)) the largest heat folding onto each pixel, as RenderWithHeat folds
  // the heatmap.
  void Fold(int x0, int y0, int w, float* out) const;
  // The same for the heatmap `edits` make of the one it was built from (a
  // TeamHeatmap robot's: TeamHeatmap::Edits), without making it: the rows
  // no edit touches are read from this fold's tables, the others are made
  // one at a time, each cell with the same sums in the same order as
  // AddHeatStamp's. The same image as Build and Fold on the edited map,
  // in O(window^2 + touched rows x nx) rather than O(cells). Thread-safe.
  void FoldEdited(int x0, int y0, int w, const std::vector<HeatEdit>& edits,
                  float* out) const;

 private:
  // Folds the map rows [lo, hi] onto the window row h, from the tables:
  // rows [0, hi] when lo is 0, [lo, ny) when hi is the last, else the one
  // row lo == hi.
  void FoldRegion(int lo, int hi, int x0, int w, float* h) const;

  const Grid<float>* heat_ = nullptr;
  int nx_ = 0, ny_ = 0;
  // (nx + 1) per row: the max of row y over columns [0, x) and [x, nx),
  // of rows [0, y] and of rows [y, ny) over the same columns.
  std::vector<float> row_before_, row_from_, top_before_, top_from_,
      bottom_before_, bottom_from_;
  // nx per row: the max of column x over rows [0, y] and over [y, ny).
  std::vector<float> top_, bottom_;
};

// The channels a model reads in a world whose lattice step is `step`: one
// pixel per lattice step, as in the worlds it was trained on (whose step
// was its `cell`), so that a move is one pixel and a way a number of moves;
// the lengths the reach channel counts in pixels (geodesic_length,
// reach_detour, reach_broad) are scaled alike, and the world's own lengths
// (blur, observe_range) stay in metres. `model` itself where the step is
// its cell. The igbnet policy, aia train and the Python channels render
// through it.
ChannelParams AtLatticeStep(const ChannelParams& model, double step);

// The channels a model reads with a sensor of `range` metres: its
// observation pixels are where the robot could measure a target, so an
// observe_range past the sensor's range is cut to it (a shorter one, the
// model's own standoff, is kept). Datasets do not record the sensor, so
// aia train renders at the model's observe_range; the igbnet policy and
// the Python channels render through this.
ChannelParams AtSensorRange(const ChannelParams& model, double range);

// A renderer keeps grids over the whole workspace at the channels' cell
// (the occupancy shares, the heatmap and its fold, the reach field): about
// 70 bytes a pixel with a policy's threads. More pixels than this are
// refused before any is made (a 10 km world at 0.5 m asked for 20 GB).
inline constexpr double kMaxChannelPixels = 4e7;
// "" when a workspace of `size` metres at params.cell stays within
// kMaxChannelPixels, else what is wrong and what would do.
std::string ChannelGridProblem(const Vec2& size, const ChannelParams& params);

class ChannelRenderer;
namespace internal {
// A copy of `renderer` whose reach channel over the workspace searches by
// cost alone (Dijkstra from every target's observation pixels, as before
// its search was bounded toward the pixels it reads): the reference its
// tests compare with.
ChannelRenderer ExhaustiveReachWorld(const ChannelRenderer& renderer);
}  // namespace internal

// Renders the channels of the robots of one map. Owns scratch memory: one
// renderer per thread.
class ChannelRenderer {
 public:
  // `occupancy`: the map's occupancy grid (world/map.h), `size`: the
  // workspace's size in metres; `lattice`: the map's motion lattice, which
  // the reach channel needs (read here, not kept).
  ChannelRenderer(const Grid<std::uint8_t>& occupancy, const Vec2& size,
                  const ChannelParams& params,
                  const Lattice* lattice = nullptr);

  const ChannelParams& params() const { return params_; }
  int height() const { return height_; }
  int width() const { return width_; }
  int channels() const { return params_.num_channels(); }
  // Floats per robot image: channels() * height * width.
  std::size_t ImageSize() const {
    return static_cast<std::size_t>(channels()) * height_ * width_;
  }
  // The occupancy share of each global pixel.
  const Grid<float>& occupancy() const { return occupancy_; }

  // Writes one robot's image, channel-major ([c][y][x]), into out[0,
  // ImageSize()). `neighbours`: this step's neighbours' positions;
  // `targets`: the robot's own fused belief (estimation/heatmap.h);
  // log_det_prior: per target; eps: the mission's threshold. Allocates
  // nothing once warm.
  // `memory`: the search points and the trail (learning/channels.h,
  // RobotMemory).
  void Render(const Vec2& self, const std::vector<Vec2>& neighbours,
              const std::vector<HeatSource>& targets,
              const std::vector<double>& log_det_prior, double eps, float* out,
              const RobotMemory& memory = {});
  // The same with the robot's heatmap given, on a grid shaped like
  // occupancy() (a team's heatmaps: estimation/heatmap.h, TeamHeatmap);
  // channel 4 needs the belief too (`targets`, `log_det_prior`, `eps`;
  // may be null without it).
  // Thread-safe.
  // `heat_fold`, when given and built from `heat` as it is now, folds the
  // heat channel in O(window^2) (the same image); with `heat_edits` too,
  // the robot's heatmap is `heat` with those edits (HeatFold::FoldEdited).
  void RenderWithHeat(const Vec2& self, const std::vector<Vec2>& neighbours,
                      const Grid<float>& heat,
                      const std::vector<HeatSource>* targets,
                      const std::vector<double>* log_det_prior, double eps,
                      float* out, const RobotMemory& memory = {},
                      const HeatFold* heat_fold = nullptr,
                      const std::vector<HeatEdit>* heat_edits = nullptr) const;
  // The pixel (u, v) of point p in the image of a robot at `self`; false
  // when p lies outside it.
  bool ImagePixel(const Vec2& self, const Vec2& p, int* u, int* v) const;
  // The heatmap parameters of these channels at a mission's eps.
  HeatmapParams Heatmap(double eps) const;

 private:
  // The neighbours plane of `plane` pixels at ChannelParams::neighbour_cap.
  void CapNeighbours(float* nbr, std::size_t plane) const;
  // Channel 4 of an image whose pixel (0, 0) is global pixel (x0, y0).
  void Reach(int x0, int y0, const Vec2& self,
             const std::vector<HeatSource>& targets,
             const std::vector<double>& log_det_prior, double eps, float* out,
             const SearchPointSets* search) const;
  // Channel 4 over the whole workspace in log space, cropped to the w x h
  // pixels from global pixel (x0, y0), scaled at the robot's pixel (sx, sy).
  // `length`: its L in metres; `detour`: dimmed by ChannelParams::
  // reach_detour where that is on; `second` (may be null): the same image
  // from each pixel's second target (ChannelParams::reach_second).
  void ReachWorld(int x0, int y0, int w, int h, int sx, int sy,
                  const std::vector<HeatSource>& targets,
                  const std::vector<double>& log_det_prior, double eps,
                  float* out, const SearchPointSets* search, double length,
                  bool detour, float* second) const;
  // ReachWorld's search (channels.cc).
  class ReachSearch;
  // ReachWorld's image of the w x h pixels from global pixel (x0, y0), from
  // the search's `costs` and the robot's own cost `self` (infinite: the
  // window's least cost is the scale).
  void ReachImage(int x0, int y0, int w, int h,
                  const std::vector<double>& costs, double self,
                  double moves_per_e, double cap, float* out) const;
  // Channel 4 over the w x h pixels from global pixel (x0, y0), scaled to 1.
  void ReachRegion(int x0, int y0, int w, int h,
                   const std::vector<HeatSource>& targets,
                   const std::vector<double>& log_det_prior, double eps,
                   float* out) const;
  // ChannelParams::reach_detour: the w x h window `out` (pixel (0, 0) the
  // global pixel (x0, y0)) dimmed by each pixel's detour from the robot's
  // pixel (sx, sy).
  void DimByDetour(int x0, int y0, int w, int h, int sx, int sy,
                   float* out) const;
  // The trail channel: the pixel `memory` came from.
  void Trail(const Vec2& self, const RobotMemory& memory, float* out) const;
  // No occupied cell of the map on the segment from a to b.
  bool Sees(const Vec2& a, const Vec2& b) const;
  // The global pixels (row-major indices, in row order) a robot may stand
  // on within the observe range of point x that see it: where the reach
  // channel's values start. Every robot asks about every target's mean (and
  // search points), mostly the same points in a step, so the answers are
  // kept per point and per thread, with no lock on the way (cleared past
  // kObservationCacheSize points, or when the thread turns to a renderer of
  // another map); thread-safe. The answer stays valid until the thread's
  // next call.
  const std::vector<int>& ObservationPixels(const Vec2& x) const;
  static constexpr std::size_t kObservationCacheSize = 1 << 16;

  ChannelParams params_;
  Vec2 size_;
  Grid<float> occupancy_;    // global pixels
  Grid<float> heat_;         // global pixels, scratch
  Grid<std::uint8_t> fine_;  // the map's occupancy (channel 4 only)
  // Per global pixel: bit m set when a robot at the pixel's lattice point may
  // move to the neighbouring pixel in direction m (reach channel only).
  std::vector<std::uint8_t> moves_;
  // The reach channel's decay per move, exp(-cell / L) as a float, to the
  // powers 0 .. nx + ny (std::pow's values).
  std::vector<double> decay_pow_;
  int height_ = 0, width_ = 0;
  // Which renderer's points a thread's kept answers are: shared by copies
  // (the same map and parameters), new for each renderer made.
  std::uint64_t observation_owner_ = 0;
  // ReachWorld searches by cost alone (internal::ExhaustiveReachWorld).
  bool exhaustive_reach_ = false;
  friend ChannelRenderer internal::ExhaustiveReachWorld(
      const ChannelRenderer& renderer);
};

namespace internal {
// Sorts (value, index) pairs by value, largest first (ties in any order),
// for values >= 0: a radix sort on the values' bits (whose order as
// unsigned integers is theirs), in three passes of 11 bits; O(n) for the
// thousands of observation pixels a window holds in a crowded world (the
// reach channel's sources).
void SortByValueDescending(std::vector<std::pair<float, int>>* items);
}  // namespace internal

}  // namespace aia

#endif  // AIA_LEARNING_CHANNELS_H_
