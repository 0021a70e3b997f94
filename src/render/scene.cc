#include "aia/render/scene.h"

#include <GL/osmesa.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "aia/core/check.h"

namespace aia {
namespace {

// The process that made the first GL context (0: none yet), and whether
// llvmpipe made its threads then. Mesa reads LP_NUM_THREADS once, when
// that context makes its screen.
std::atomic<pid_t> g_gl_process{0};
std::atomic<bool> g_gl_threads{false};

void NoteFirstContext() {
  const char* threads = std::getenv("LP_NUM_THREADS");
  pid_t none = 0;
  if (g_gl_process.compare_exchange_strong(none, ::getpid()))
    g_gl_threads = threads == nullptr || std::string(threads) != "0";
}

// Refuses to go on in a process that cannot render.
void CheckCanRender() {
  if (const std::string why = RenderForkProblem(); !why.empty())
    throw std::runtime_error(why);
}

}  // namespace

std::string RenderForkProblem() {
  const pid_t first = g_gl_process.load();
  if (first == 0 || first == ::getpid() || !g_gl_threads.load()) return "";
  return "this process was forked from one that had rendered (pid " +
         std::to_string(first) +
         ") and lacks the threads Mesa's llvmpipe made there, for which a "
         "render would wait for ever: use multiprocessing's 'spawn' or "
         "'forkserver' start method, or set LP_NUM_THREADS=0 before the "
         "first render";
}

void OsMesaDeleter::operator()(osmesa_context* context) const {
  OSMesaDestroyContext(context);
}

void MjvSceneDeleter::operator()(mjvScene* scene) const {
  mjv_freeScene(scene);
  delete scene;
}

void MjrContextDeleter::operator()(mjrContext* context) const {
  mjr_freeContext(context);
  delete context;
}

SceneRenderer::SceneRenderer(const mjModel* model,
                             const SceneSettings& settings)
    : settings_(settings) {
  AIA_CHECK(model != nullptr && settings.width > 0 && settings.height > 0);
  model_ = MjModelPtr(mj_copyModel(nullptr, model));
  AIA_CHECK(model_ != nullptr);
  mjVisual& vis = model_->vis;
  vis.global.offwidth = settings.width;
  vis.global.offheight = settings.height;
  vis.quality.offsamples = settings.samples;
  // The generated model lights the floor with a directional light from above;
  // a softer headlight keeps the light floor from saturating to white.
  vis.headlight.ambient[0] = vis.headlight.ambient[1] =
      vis.headlight.ambient[2] = 0.25f;
  vis.headlight.diffuse[0] = vis.headlight.diffuse[1] =
      vis.headlight.diffuse[2] = 0.2f;
  vis.headlight.specular[0] = vis.headlight.specular[1] =
      vis.headlight.specular[2] = 0.0f;
  // A plane's third size is only the spacing of its render grid: MuJoCo draws
  // the floor as (size / spacing)^2 quads, 40 000 for the generated 0.1 m,
  // which halves the frame rate under software GL and changes no pixel (the
  // lights are directional). A 4 x 4 grid renders the same image.
  for (int g = 0; g < model_->ngeom; ++g) {
    if (model_->geom_type[g] != mjGEOM_PLANE) continue;
    mjtNum* size = model_->geom_size + 3 * g;
    size[2] = std::max(size[2], 0.5 * std::max(size[0], size[1]));
  }
  // Robots and targets are a few pixels across seen from above: 16-gons do,
  // and with 80 robots this more than doubles the frame rate.
  vis.quality.numslices = std::min(vis.quality.numslices, 16);
  vis.quality.numstacks = std::min(vis.quality.numstacks, 8);

  CheckCanRender();
  NoteFirstContext();
  gl_ = OsMesaPtr(OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr));
  if (!gl_) throw std::runtime_error("cannot create an OSMesa context");
  gl_buffer_.resize(static_cast<size_t>(settings.width) * settings.height * 4);
  if (!OSMesaMakeCurrent(gl_.get(), gl_buffer_.data(), GL_UNSIGNED_BYTE,
                         settings.width, settings.height))
    throw std::runtime_error("cannot make the OSMesa context current");

  scene_ = MjvScenePtr(new mjvScene);
  mjv_defaultScene(scene_.get());
  mjv_makeScene(model_.get(), scene_.get(),
                model_->ngeom + model_->nsite + 100);
  scene_->flags[mjRND_SHADOW] = settings.shadows ? 1 : 0;
  scene_->flags[mjRND_REFLECTION] = 0;
  scene_->flags[mjRND_SKYBOX] = 0;

  context_ = MjrContextPtr(new mjrContext);
  mjr_defaultContext(context_.get());
  mjr_makeContext(model_.get(), context_.get(), mjFONTSCALE_100);
  mjr_setBuffer(mjFB_OFFSCREEN, context_.get());
  if (context_->currentBuffer != mjFB_OFFSCREEN ||
      context_->offWidth < settings.width ||
      context_->offHeight < settings.height)
    throw std::runtime_error("MuJoCo's offscreen buffer is not available (" +
                             std::to_string(context_->offWidth) + "x" +
                             std::to_string(context_->offHeight) + ")");
  mjv_defaultOption(&option_);
  mjv_defaultCamera(&camera_);
  rgb_.resize(static_cast<size_t>(settings.width) * settings.height * 3);
}

SceneRenderer::~SceneRenderer() {
  // MuJoCo frees its GL objects in whatever context is current: make it ours.
  if (gl_)
    OSMesaMakeCurrent(gl_.get(), gl_buffer_.data(), GL_UNSIGNED_BYTE,
                      settings_.width, settings_.height);
}

void SceneRenderer::Render(const mjData* data, const mjvCamera& camera,
                           cv::Mat* bgr) {
  CheckCanRender();
  const int w = settings_.width, h = settings_.height;
  AIA_CHECK(
      OSMesaMakeCurrent(gl_.get(), gl_buffer_.data(), GL_UNSIGNED_BYTE, w, h));
  mjr_setBuffer(mjFB_OFFSCREEN, context_.get());
  camera_ = camera;
  // mjv_updateScene takes mjData* but only reads the state (it borrows and
  // returns MuJoCo's scratch stack); the simulation is not changed.
  mjv_updateScene(model_.get(), const_cast<mjData*>(data), &option_, nullptr,
                  &camera_, mjCAT_ALL, scene_.get());
  const mjrRect viewport = {0, 0, w, h};
  mjr_render(viewport, scene_.get(), context_.get());
  mjr_readPixels(rgb_.data(), nullptr, viewport, context_.get());
  // GL rows run bottom to top; OpenCV's top to bottom, in BGR order.
  const cv::Mat rgb(h, w, CV_8UC3, rgb_.data());
  cv::flip(rgb, flipped_, 0);
  cv::cvtColor(flipped_, *bgr, cv::COLOR_RGB2BGR);
}

void SceneRenderer::SetGroupVisible(int group, bool visible) {
  AIA_CHECK(group >= 0 && group < mjNGROUP);
  option_.geomgroup[group] = option_.sitegroup[group] = visible ? 1 : 0;
}

}  // namespace aia
