// One video frame of a mission: the MuJoCo scene seen from straight above,
// with the state that physics does not show drawn over it: sensing
// discs, this step's communication edges (lost packets red and dashed),
// trails, each target's truth and the team's best estimate with its 2-sigma
// ellipse coloured by det Sigma against eps, failed robots, an optional
// uncertainty heatmap, a heads-up line and a legend beside the workspace.
// What is drawn, and how big, follows the scale (docs/rendering.md, "At
// scale"): with many robots or few pixels per metre, robots and targets
// become dots (the target's coloured by det Sigma against eps), sensing discs
// one tint, trails short, and a graph too dense to read is left out. The
// overlay is plain data filled by the caller (runtime's `aia render`), so
// that this module needs no episode; it draws, it decides nothing.
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
#include "aia/render/edge_mode.h"
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
  double seconds = 0.0;  // the simulated clock at this frame
  int localized = 0;     // targets with min_i det Sigma_i^k <= eps
  std::string policy;
  std::uint64_t seed = 0;
  double eps = 0.1;
  double sensor_range = 2.0;
  std::vector<Vec2> robots;  // positions now, from the physics
  // Headings (radians from +x) of wheeled robots, drawn as a tick from the
  // centre through the rim; empty for point robots, which have none.
  std::vector<double> headings;
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
  // recent past; with more than 10 robots each keeps
  // max(5, 500 / robots) steps at most (TrailSteps).
  int trail_steps = 50;
  float heat_alpha = 0.6f;  // opacity of the heatmap where H >= 1
  EdgeMode edges = EdgeMode::kAuto;
  // kAuto draws the delivered messages while their lines (one per pair,
  // length x width) would cover at most this share of the workspace's
  // pixels; a denser web is a haze that hides the map.
  double edge_ink = 0.12;
};

// Decision steps of trail each of `robots` robots keeps with `trail_steps`
// asked for: at most 500 robot-steps of trail in all, but at least 5 each.
int TrailSteps(int trail_steps, int robots);

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
  // The workspace with its border walls, at the walls' tops, in whole pixels.
  const cv::Rect& world_rect() const { return world_rect_; }
  // Where the legend is drawn, beside the workspace; empty: no room for one.
  const cv::Rect& legend_rect() const { return legend_rect_; }
  // Whether robots and targets are drawn as dots by the overlay (too small or
  // too many for MuJoCo's bodies to show; MuJoCo's image of the static world
  // is then rendered once and reused).
  bool compact() const { return compact_; }
  // Whether the last frame drew this step's delivered messages.
  bool drew_messages() const { return drew_messages_; }
  // Wall seconds spent so far in MuJoCo's render and read-back, and in the
  // heatmap layer and overlays.
  double scene_seconds() const { return scene_seconds_; }
  double overlay_seconds() const { return overlay_seconds_; }

 private:
  // What the legend shows; it is rebuilt when this changes.
  struct LegendKey {
    bool heat = false;
    bool tint = false;     // sensing discs as one tint
    bool messages = true;  // delivered messages drawn
    bool lost = true;      // lost messages drawn
    bool operator==(const LegendKey& o) const {
      return heat == o.heat && tint == o.tint && messages == o.messages &&
             lost == o.lost;
    }
  };

  enum class LegendIcon {
    kRobot,
    kSensing,
    kMessage,
    kLost,
    kTarget,
    kUncertain,
    kLocalized,
    kFailed,
    kHeat
  };

  void DrawHeatmap(cv::Mat* image) const;
  // The key to the symbols, in the column right of the workspace that the
  // view keeps free when the image is wide enough; drawn with the overlay's
  // own glyphs.
  void BuildLegend(const LegendKey& key);
  std::vector<std::pair<LegendIcon, const char*>> LegendRowsFor(
      const LegendKey& key) const;
  // One row's icon, centred at height `cy` of the legend.
  void DrawLegendIcon(LegendIcon icon, double cy, const LegendKey& key);
  // Whether this step's delivered messages are drawn (kAuto: the ink rule;
  // decided once per step and graph).
  bool MessagesShown(const FrameOverlay& overlay);
  // The overlays, in drawing order: sensing discs and delivered messages
  // (returns whether messages were shown; *tint: the discs as one tint),
  // lost messages, trails, targets, robots, then the legend and the
  // heads-up line.
  void DrawOverlay(const FrameOverlay& overlay, cv::Mat* image);
  bool DrawSensingAndMessages(const FrameOverlay& o, cv::Mat* image,
                              bool* tint);
  void DrawLostMessages(const FrameOverlay& o, cv::Mat* image);
  void DrawTrails(const FrameOverlay& o, cv::Mat* image);
  void DrawTargets(const FrameOverlay& o, cv::Mat* image);
  void DrawRobots(const FrameOverlay& o, cv::Mat* image);
  void DrawHeadsUp(const FrameOverlay& o, cv::Mat* image) const;

  const Simulation& sim_;
  FrameSettings settings_;
  SceneRenderer scene_;
  TopDownView view_;
  mjvCamera camera_;
  double robot_radius_;
  double world_area_m2_;  // the workspace's floor, square metres
  bool compact_ = false;
  bool wheeled_ = false;  // robots have a heading to draw
  int trail_steps_ = 0;
  std::vector<std::deque<Vec2>> trails_;
  cv::Mat frame_, layer_;
  cv::Mat background_;  // compact: MuJoCo's image of the static world
  cv::Rect world_rect_;
  cv::Rect heat_rect_;
  cv::Mat heat_bgr_, heat_alpha_;  // over heat_rect_; empty: no heatmap
  cv::Rect legend_room_;           // empty: no room for a legend
  cv::Rect legend_rect_;           // the part the legend covers
  cv::Mat legend_;
  LegendKey legend_key_;
  bool legend_built_ = false;
  // The kAuto decision for the graph of one step.
  int messages_step_ = -1;
  const void* messages_graph_ = nullptr;
  size_t messages_directed_ = 0;
  bool messages_shown_ = true;
  bool drew_messages_ = false;
  std::vector<cv::Point> pixels_;    // scratch: robots' floor pixels (shifted)
  std::vector<cv::Point> polyline_;  // scratch
  double scene_seconds_ = 0.0, overlay_seconds_ = 0.0;
};

}  // namespace aia

#endif  // AIA_RENDER_FRAME_RENDERER_H_
