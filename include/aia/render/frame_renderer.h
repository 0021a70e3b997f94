// One video frame of a mission: the MuJoCo scene seen from straight above,
// with the state that physics does not show drawn over it: sensing
// discs, this step's communication edges (lost packets red and dashed),
// trails, each target's truth and the team's best estimate with its 2-sigma
// ellipse coloured by det Sigma against eps, failed robots, an optional
// uncertainty heatmap, and a heads-up line. The overlay is plain data filled
// by the caller (runtime's `aia render`), so that this module needs no
// episode; it draws, it decides nothing.
#ifndef AIA_RENDER_FRAME_RENDERER_H_
#define AIA_RENDER_FRAME_RENDERER_H_

#include <cstdint>
#include <deque>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "aia/core/grid.h"
#include "aia/core/types.h"
#include "aia/render/scene.h"
#include "aia/render/view.h"
#include "aia/sim/simulation.h"
#include "aia/world/map.h"

namespace aia {

// One target as a frame shows it.
struct TargetOverlay {
  Vec2 truth{0.0, 0.0};  // true position now
  // The team's best estimate: the belief of the active robot with the
  // smallest det Sigma for this target.
  Vec2 mean{0.0, 0.0};
  Mat2 cov = Mat2::Identity();  // its position covariance (the ellipse)
  double det = 1.0;             // its det Sigma, judged against eps
  double weight =
      1.0;  // its heat weight w_k (estimation/heatmap.h), for the colour
};

// What a frame shows beyond the physics.
struct FrameOverlay {
  int step = 0;
  int max_steps = 0;
  int localized = 0;  // targets with min_i det Sigma_i^k <= eps
  std::string policy;
  std::uint64_t seed = 0;
  double eps = 0.1;
  double sensor_range = 2.0;
  std::vector<Vec2> robots;  // positions now, from the physics
  std::vector<std::uint8_t> active;
  // This step's graph: neighbors[i] = robots whose message i received; lost =
  // directed edges (receiver, sender) that were in range but lost.
  const std::vector<std::vector<int>>* neighbors = nullptr;
  const std::vector<std::pair<int, int>>* lost = nullptr;
  std::vector<TargetOverlay> targets;
  int heatmap_robot = -1;  // named in the heads-up line (the layer: SetHeatmap)
};

struct FrameSettings {
  SceneSettings scene;
  // Decision steps of trail kept per robot; 0 keeps the whole mission. A
  // long mission's full trails bury the map, so the default shows the
  // recent past.
  int trail_steps = 50;
  float heat_alpha = 0.6f;  // opacity of the heatmap where H >= 1
};

// Height of the band kept free at the top of the image for the heads-up line.
int HudBandPixels(int image_height);

class FrameRenderer {
 public:
  // Renders `sim`'s model (the map gives the workspace to frame). Throws
  // std::runtime_error when no GL context can be made.
  FrameRenderer(const Simulation& sim, const Map& map,
                const FrameSettings& settings);

  // Appends each robot's position to its trail (once per decision step; the
  // current position always closes the trail).
  void AddTrailPoints(const std::vector<Vec2>& robots);
  // The heatmap layer drawn under the overlays (over the floor); nullptr: none.
  // H is shown clamped to [0, 1]. Call when the heat changes, not per frame.
  void SetHeatmap(const Grid<float>* heat);

  // Renders the simulation's current state with the overlay. The image
  // (CV_8UC3, BGR) stays valid until the next call.
  const cv::Mat& Render(const FrameOverlay& overlay);

  const TopDownView& view() const { return view_; }
  // Wall seconds spent so far in MuJoCo's render and read-back, and in the
  // heatmap layer and overlays.
  double scene_seconds() const { return scene_seconds_; }
  double overlay_seconds() const { return overlay_seconds_; }

 private:
  void DrawHeatmap(cv::Mat* image) const;
  // The key to the symbols, in the margin right of the workspace when there
  // is room (a 4:3 image of a square workspace has about 90 px at 640 wide).
  void BuildLegend(bool heat);
  void DrawOverlay(const FrameOverlay& overlay, cv::Mat* image);

  const Simulation& sim_;
  FrameSettings settings_;
  SceneRenderer scene_;
  TopDownView view_;
  mjvCamera camera_;
  double robot_radius_;
  std::vector<std::deque<Vec2>> trails_;
  cv::Mat frame_, layer_;
  cv::Rect heat_rect_;
  cv::Mat heat_bgr_, heat_alpha_;  // over heat_rect_; empty: no heatmap
  cv::Rect legend_room_;           // empty: no room for a legend
  cv::Rect legend_rect_;           // the part the legend covers
  cv::Mat legend_;
  bool legend_heat_ = false;
  std::vector<cv::Point> pixels_;  // scratch: robots' floor pixels (shifted)
  double scene_seconds_ = 0.0, overlay_seconds_ = 0.0;
};

}  // namespace aia

#endif  // AIA_RENDER_FRAME_RENDERER_H_
