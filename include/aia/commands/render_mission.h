// `aia render`: one mission as an H.264 MP4, frames taken from the physics
// every 1/fps seconds of simulated time, so motion is as smooth as the
// simulation; optionally every k-th frame as PNG. The mission runs and ends
// exactly as under `aia run` (same seed, same outcome); its summary and trace
// are written next to the video.
#ifndef AIA_COMMANDS_RENDER_MISSION_H_
#define AIA_COMMANDS_RENDER_MISSION_H_

#include <optional>
#include <string>

#include "aia/core/fields.h"
#include "aia/render/edge_mode.h"
#include "aia/runtime/mission.h"

namespace aia {

struct RenderOptions {
  std::string scenario_path;
  CommandOverrides overrides;
  std::string out_file;  // FILE.mp4; its directory is created
  // Overrides of the scenario's render section (applied like --set, after
  // the mission flags; `aia render` passes its --width, ... as text in
  // overrides.flags instead, read as the keys).
  std::optional<int> width, height, fps;
  std::optional<int> heatmap_robot;  // render.follow_robot; -1: none
  std::string frames_dir;            // non-empty: PNG frames written here
  int frames_every = 1;              // write video frames 0, k, 2k, ... as PNG
  double hold = 1.0;                 // seconds the final frame is held
  EdgeMode edges = EdgeMode::kAuto;  // render/frame_renderer.h
  double memory_budget = 8.0;        // GiB; RenderMemoryNeed must fit
  bool progress = true;

  // The video's own flags, declared once (their help and range checks).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(frames_every)
                 .In(AtLeast(1))
                 .Doc("with --frames: write every k-th frame"));
    a->Visit(AIA_FIELD(hold)
                 .In(Between(0.0, 60.0))
                 .Doc("seconds the final frame is held"));
    a->Visit(AIA_FIELD(edges).Doc(
        "communication edges drawn: auto (lost messages, and the delivered "
        "ones while they stay readable), all, lost or none"));
    a->Visit(AIA_FIELD(memory_budget)
                 .In(Between(0.25, 4096.0))
                 .Doc("GiB the render may take: a size that needs more "
                      "(512 MiB + 256 bytes per pixel) is refused before "
                      "any work"));
  }
};

// The memory a render of `width` x `height` pixels takes at most, in bytes:
// 512 MiB (the process, the mission, the static scene) and 256 bytes per
// pixel (the GL buffers and frame copies, about 40, and the H.264 encoder's
// look-ahead of some 50 frames on its 3 threads, about 190; measured 230 in
// all at 1024 to 4096 pixels square, docs/hardening.md). Frames are encoded
// as they are rendered, never held: the need does not grow with the
// video's length.
double RenderMemoryNeed(int width, int height);

struct RenderResult {
  MissionSummary mission;
  std::string video;  // the MP4's path
  std::string codec;  // "avc1" (H.264) or "mp4v"
  int frames = 0;     // frames in the video
  int fps = 30;
  int width = 0, height = 0;
  double video_seconds = 0.0;      // frames / fps
  double frames_per_second = 0.0;  // rendering speed: frames per wall second
  int png_frames = 0;
};

// Renders the mission; writes FILE.mp4, and next to it the result files of
// `aia run` named FILE_STEM.summary.json (plus a "video" object),
// FILE_STEM.trace.csv, FILE_STEM.effective.yaml, ... (runtime/mission.h).
// Throws InputError for bad input (flags, scenario, an output path that
// cannot be written).
RenderResult RenderMission(const RenderOptions& options);

}  // namespace aia

#endif  // AIA_COMMANDS_RENDER_MISSION_H_
