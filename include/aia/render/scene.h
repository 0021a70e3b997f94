// Headless MuJoCo rendering through OSMesa (no X server, no GPU): a software
// GL context, MuJoCo's scene and render context, and read-back of
// the offscreen buffer as an OpenCV BGR image, top row first.
#ifndef AIA_RENDER_SCENE_H_
#define AIA_RENDER_SCENE_H_

#include <mujoco/mujoco.h>

#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "aia/sim/simulation.h"

struct osmesa_context;  // OSMesaContext, from <GL/osmesa.h>

namespace aia {

struct OsMesaDeleter {
  void operator()(osmesa_context* context) const;
};
struct MjvSceneDeleter {
  void operator()(mjvScene* scene) const;
};
struct MjrContextDeleter {
  void operator()(mjrContext* context) const;
};
using OsMesaPtr = std::unique_ptr<osmesa_context, OsMesaDeleter>;
using MjvScenePtr = std::unique_ptr<mjvScene, MjvSceneDeleter>;
using MjrContextPtr = std::unique_ptr<mjrContext, MjrContextDeleter>;

struct SceneSettings {
  int width = 640;
  int height = 480;
  // Shadows cost about two thirds of the frame rate (measured at 640x480
  // under OSMesa: 34 frames/s with them, 97 without) and add little to a
  // view from straight above.
  bool shadows = false;
  // Multisampling of MuJoCo's offscreen buffer. 4x costs about 4x the render
  // time under software GL; seen from above, box edges are axis-aligned and
  // the overlays are anti-aliased by OpenCV, so none is needed.
  int samples = 0;
};

// Why this process cannot render, "" where it can. Mesa's llvmpipe makes
// its rasterizer threads with the process's first GL context and keeps
// them for the process's life; a process forked since (os.fork, Python
// multiprocessing's default start method on Linux) has none of them, and
// its first render waited for them for ever. A first context made with
// LP_NUM_THREADS=0 has no threads to miss.
std::string RenderForkProblem();

// Renders one model's state. The renderer keeps its own copy of the model,
// with the offscreen size, sampling and lights it needs, so that the
// simulation's model stays untouched. One GL context per renderer; each
// Render() makes it current, so several renderers may live in one thread.
class SceneRenderer {
 public:
  // Throws std::runtime_error when no GL context can be made (also in a
  // process that cannot render: RenderForkProblem()).
  SceneRenderer(const mjModel* model, const SceneSettings& settings);
  ~SceneRenderer();
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;

  // Renders `data` (a state of the model given at construction) seen by
  // `camera` into `bgr` (CV_8UC3, width x height, top row first).
  void Render(const mjData* data, const mjvCamera& camera, cv::Mat* bgr);
  // Whether geoms and sites of `group` (0 to mjNGROUP - 1) are drawn; by
  // default MuJoCo's: groups 0, 1 and 2.
  void SetGroupVisible(int group, bool visible);

  const mjModel* model() const { return model_.get(); }
  int width() const { return settings_.width; }
  int height() const { return settings_.height; }

 private:
  SceneSettings settings_;
  MjModelPtr model_;
  std::vector<unsigned char> gl_buffer_;  // OSMesa's default framebuffer
  OsMesaPtr gl_;                          // outlives the MuJoCo render context
  MjvScenePtr scene_;
  MjrContextPtr context_;
  mjvOption option_;
  mjvCamera camera_;
  std::vector<unsigned char> rgb_;  // read-back, bottom row first
  cv::Mat flipped_;                 // scratch: the read-back top row first
};

}  // namespace aia

#endif  // AIA_RENDER_SCENE_H_
