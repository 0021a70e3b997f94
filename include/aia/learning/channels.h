// I-GBNet's input (docs/learning.md, Channels): per robot, four images over
// the workspace, one definition shared by the dataset reader, the trainer,
// the igbnet policy (Python reads the states: tools/igbnet.py). No torch here.
//   0 occupancy: the share of the pixel covered by obstacles (1 outside the
//     workspace);
//   1 own position: 1 at the robot's pixel;
//   2 neighbours: the number of this step's neighbours (self excluded) in
//     each pixel;
//   3 heat: the robot's own fused belief projected as the heatmap of
//     estimation/heatmap.h.
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

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "aia/core/grid.h"
#include "aia/core/types.h"
#include "aia/estimation/heatmap.h"

namespace aia {

inline constexpr int kNumChannels = 4;

enum class ChannelFrame { kGlobal = 0, kCentred = 1 };
std::string_view ChannelFrameName(ChannelFrame frame);
// "global" or "centred" (also "centered"); false for anything else.
bool ParseChannelFrame(std::string_view text, ChannelFrame* frame);

struct ChannelParams {
  ChannelFrame frame = ChannelFrame::kCentred;
  double cell = 0.5;    // metres per pixel
  int window = 40;      // centred frame: pixels per side
  double blur = 1.0;    // the heatmap's s, metres
  double cutoff = 4.0;  // the heatmap's cut-off, standard deviations
};

// Renders the channels of the robots of one map. Owns scratch memory: one
// renderer per thread.
class ChannelRenderer {
 public:
  // `occupancy`: the map's occupancy grid (world/map.h), `size`: the
  // workspace's size in metres.
  ChannelRenderer(const Grid<std::uint8_t>& occupancy, const Vec2& size,
                  const ChannelParams& params);

  const ChannelParams& params() const { return params_; }
  int height() const { return height_; }
  int width() const { return width_; }
  // Floats per robot image: kNumChannels * height * width.
  std::size_t ImageSize() const {
    return static_cast<std::size_t>(kNumChannels) * height_ * width_;
  }
  // The occupancy share of each global pixel.
  const Grid<float>& occupancy() const { return occupancy_; }

  // Writes one robot's image, channel-major ([c][y][x]), into out[0,
  // ImageSize()). `neighbours`: this step's neighbours' positions;
  // `targets`: the robot's own fused belief (estimation/heatmap.h);
  // log_det_prior: per target; eps: the mission's threshold. Allocates
  // nothing once warm.
  void Render(const Vec2& self, const std::vector<Vec2>& neighbours,
              const std::vector<HeatSource>& targets,
              const std::vector<double>& log_det_prior, double eps, float* out);
  // The same with the robot's heatmap given, on a grid shaped like
  // occupancy() (a team's heatmaps: estimation/heatmap.h, TeamHeatmap).
  // Thread-safe.
  void RenderWithHeat(const Vec2& self, const std::vector<Vec2>& neighbours,
                      const Grid<float>& heat, float* out) const;
  // The heatmap parameters of these channels at a mission's eps.
  HeatmapParams Heatmap(double eps) const;

 private:
  ChannelParams params_;
  Vec2 size_;
  Grid<float> occupancy_;  // global pixels
  Grid<float> heat_;       // global pixels, scratch
  int height_ = 0, width_ = 0;
};

}  // namespace aia

#endif  // AIA_LEARNING_CHANNELS_H_
