// The picture of an episode for `aia render` and the Python package.
#ifndef AIA_COMMANDS_EPISODE_PICTURE_H_
#define AIA_COMMANDS_EPISODE_PICTURE_H_

#include "aia/core/grid.h"
#include "aia/estimation/heatmap.h"
#include "aia/render/frame_renderer.h"
#include "aia/runtime/episode.h"

namespace aia {

// The picture of an episode as `aia render` draws it: the overlay (the
// team's best estimates, the trails, the followed robot's heatmap) kept in
// step with the episode, and frames of the physics as it is now. aia render
// films it; the Python package's Mission.render draws single frames.
class EpisodePicture {
 public:
  // `renderer` (of the episode's simulation) must outlive the picture.
  EpisodePicture(const Episode& episode, FrameRenderer* renderer);
  // Once at the start and after every decision step.
  void AfterStep(const Episode& episode);
  // A frame of the physics now (BGR, valid until the next call).
  const cv::Mat& Render(const Episode& episode);

 private:
  FrameRenderer* renderer_;
  int heat_robot_ = -1;
  Grid<float> heat_;
  HeatmapParams heat_params_;
  FrameOverlay overlay_;
};

}  // namespace aia

#endif  // AIA_COMMANDS_EPISODE_PICTURE_H_
