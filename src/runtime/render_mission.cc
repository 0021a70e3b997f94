#include "aia/runtime/render_mission.h"

#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "aia/core/error.h"
#include "aia/core/io.h"
#include "aia/estimation/heatmap.h"
#include "aia/render/frame_renderer.h"
#include "aia/render/video.h"
#include "aia/scenario/loader.h"

namespace aia {
namespace {

namespace fs = std::filesystem;

// Largest image side: far beyond any video, well within software GL's limits.
constexpr int kMaxSide = 8192;

// An error about a value that came from a flag or, without one, from the file.
InputError ValueError(const Scenario& s, bool from_flag,
                      const std::string& flag, const std::string& key,
                      const std::string& what) {
  if (from_flag) return InputError("command line", 0, flag, what);
  return InputError(s.file.empty() ? "scenario" : s.file, s.LineOf(key), key,
                    what);
}

// Applies and checks the render overrides. H.264 in 4:2:0 needs even sides;
// frames come from physics substeps, so at most one per substep.
void ApplyRenderOptions(const RenderOptions& o, Scenario* s) {
  if (o.width) s->render.width = *o.width;
  if (o.height) s->render.height = *o.height;
  if (o.fps) s->render.fps = *o.fps;
  const struct {
    int value;
    bool flag;
    const char* name;
    const char* key;
  } sides[] = {
      {s->render.width, o.width.has_value(), "--width", "render.width"},
      {s->render.height, o.height.has_value(), "--height", "render.height"}};
  for (const auto& side : sides) {
    if (side.value < 16 || side.value > kMaxSide || side.value % 2 != 0)
      throw ValueError(*s, side.flag, side.name, side.key,
                       "must be an even number of pixels in [16, " +
                           std::to_string(kMaxSide) +
                           "] (H.264 needs even sides), got " +
                           std::to_string(side.value));
  }
  const int max_fps =
      static_cast<int>(std::floor(1.0 / s->physics.timestep + 1e-9));
  if (s->render.fps < 1 || s->render.fps > max_fps)
    throw ValueError(*s, o.fps.has_value(), "--fps", "render.fps",
                     "must be in [1, " + std::to_string(max_fps) +
                         "] (at most one frame per physics step of " +
                         std::to_string(s->physics.timestep) + " s), got " +
                         std::to_string(s->render.fps));
  if (o.heatmap_robot) {
    const int n = s->robots.count;
    if (*o.heatmap_robot < -1 || *o.heatmap_robot >= n)
      throw InputError("command line", 0, "--heatmap",
                       "must be -1 (none) or a robot index in [0, " +
                           std::to_string(n - 1) + "], got " +
                           std::to_string(*o.heatmap_robot));
    s->render.follow_robot = *o.heatmap_robot;
  }
  if (o.frames_every < 1)
    throw InputError(
        "command line", 0, "--frames-every",
        "must be at least 1, got " + std::to_string(o.frames_every));
  if (!(o.hold_seconds >= 0.0 && o.hold_seconds <= 60.0))
    throw InputError("command line", 0, "--hold", "must be in [0, 60] seconds");
}

// The overlay's per-step part (beliefs change only when a step ends).
void UpdateTargets(const Episode& e, const std::vector<double>& log_det_prior,
                   FrameOverlay* o) {
  const int n = e.world().NumRobots(), m = e.world().NumTargets();
  const double eps = e.scenario().mission.eps;
  o->targets.resize(m);
  for (int k = 0; k < m; ++k) {
    int best = -1;
    double best_det = std::numeric_limits<double>::infinity();
    for (int i = 0; i < n; ++i) {
      if (!e.comm().Active(i)) continue;
      if (best < 0 || e.Det(i, k) < best_det) {
        best = i;
        best_det = e.Det(i, k);
      }
    }
    if (best < 0) best = 0;  // every robot failed: show robot 0's belief
    TargetOverlay& t = o->targets[k];
    t.mean = e.beliefs().PositionMean(best, k);
    t.cov = e.beliefs().PositionCovariance(best, k);
    t.det = e.Det(best, k);
    t.weight = HeatWeight(e.beliefs().LogDetCovariance(best, k),
                          log_det_prior[k], eps);
  }
  o->step = e.step();
  o->localized = e.NumLocalized();
}

// The overlay's per-frame part: where things are in the physics now.
void UpdatePositions(const Episode& e, FrameOverlay* o) {
  const Simulation& sim = e.sim();
  o->robots.resize(sim.num_robots());
  for (int i = 0; i < sim.num_robots(); ++i)
    o->robots[i] = sim.RobotPosition(i);
  for (int k = 0; k < sim.num_targets(); ++k)
    o->targets[k].truth = sim.TargetPosition(k);
  o->active = e.comm().active();
}

}  // namespace

RenderResult RenderMission(const RenderOptions& options) {
  const PolicyRegistry registry = AllPolicies();
  Scenario scenario = LoadScenario(options.scenario_path);
  ApplyOverrides(options.overrides, registry, &scenario);
  ApplyRenderOptions(options, &scenario);

  const fs::path out(options.out_file);
  if (options.out_file.empty() || out.extension() != ".mp4" ||
      out.stem().empty())
    throw InputError("command line", 0, "--out",
                     "must name an .mp4 file, got '" + options.out_file + "'");
  const fs::path side_dir = out.parent_path();
  const std::string stem = out.stem().string();
  const std::string summary_path =
      (side_dir / (stem + ".summary.json")).string();
  const std::string trace_path = (side_dir / (stem + ".trace.csv")).string();

  const auto t0 = std::chrono::steady_clock::now();
  auto episode = MakeEpisode(scenario, registry);
  MakeOutputDir(out.parent_path().string(), "--out");
  MakeOutputDir(options.frames_dir, "--frames");
  const World& world = episode->world();
  const int fps = scenario.render.fps;
  const int width = scenario.render.width, height = scenario.render.height;

  FrameSettings settings;
  settings.scene.width = width;
  settings.scene.height = height;
  FrameRenderer renderer(episode->sim(), world, settings);
  std::unique_ptr<Mp4Writer> video;
  try {
    video = std::make_unique<Mp4Writer>(options.out_file, width, height, fps);
  } catch (const std::runtime_error& e) {
    throw InputError("command line", 0, "--out", e.what());
  }
  TraceWriter trace(trace_path, world.NumRobots());
  trace.Write(*episode);

  // The heatmap of one robot's fused belief (SPEC section 8), once per step.
  const int heat_robot = scenario.render.follow_robot;
  std::vector<double> log_det_prior;
  for (const TargetInstance& t : world.targets)
    log_det_prior.push_back(std::log(t.prior_cov.determinant()));
  Grid<float> heat;
  HeatmapParams heat_params;
  heat_params.eps = scenario.mission.eps;
  heat_params.blur = 0.5 * scenario.sensor.range;
  if (heat_robot >= 0)
    heat = MakeHeatmapGrid(world.size, world.occupancy.cell());

  FrameOverlay overlay;
  overlay.max_steps = scenario.mission.max_steps;
  overlay.policy = std::string(episode->policy().name());
  overlay.seed = scenario.seed;
  overlay.eps = scenario.mission.eps;
  overlay.sensor_range = scenario.sensor.range;
  overlay.neighbors = &episode->comm().AllNeighbors();
  overlay.lost = &episode->comm().Lost();
  overlay.heatmap_robot = heat_robot;
  const auto after_step = [&](const Episode& e) {
    UpdateTargets(e, log_det_prior, &overlay);
    renderer.AddTrailPoints(e.robot_positions());
    if (heat_robot >= 0) {
      ProjectHeatmap(e.beliefs(), heat_robot, log_det_prior, heat_params,
                     &heat);
      renderer.SetHeatmap(&heat);
    }
  };

  int png_frames = 0;
  double write_seconds = 0.0;  // H.264 encoding and PNG files
  const auto emit = [&](const Episode& e) -> const cv::Mat& {
    UpdatePositions(e, &overlay);
    const cv::Mat& image = renderer.Render(overlay);
    const auto t_write = std::chrono::steady_clock::now();
    if (!options.frames_dir.empty() &&
        video->frames() % options.frames_every == 0) {
      char name[32];
      std::snprintf(name, sizeof(name), "frame_%06d.png", video->frames());
      const std::string path = (fs::path(options.frames_dir) / name).string();
      if (!cv::imwrite(path, image))
        throw InputError("command line", 0, "--frames", "cannot write " + path);
      ++png_frames;
    }
    video->Write(image);
    write_seconds += std::chrono::duration<double>(
                         std::chrono::steady_clock::now() - t_write)
                         .count();
    return image;
  };

  // Frames: the start; then, during the physics, one each time another 1/fps
  // seconds of simulated time have passed (frame f at f / fps s); then the
  // state after the last step's fusion, held `hold` frames. The overlay's
  // beliefs and graph are those of the last completed step.
  ProgressLine progress(options.progress);
  const int m = world.NumTargets();
  const double frame_dt = 1.0 / fps;
  double sim_time = 0.0, next_frame = frame_dt;
  after_step(*episode);
  emit(*episode);
  while (!episode->done()) {
    const double step_start = sim_time;
    episode->Step([&](const Episode& e, double elapsed) {
      sim_time = step_start + elapsed;
      if (sim_time + 1e-9 >= next_frame) {
        emit(e);
        next_frame += frame_dt;
      }
    });
    after_step(*episode);
    trace.Write(*episode);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
            .count();
    char buf[200];
    std::snprintf(
        buf, sizeof(buf),
        "[aia render] %s  step %d/%d  localized %d/%d  frame %d  %.1f fps",
        overlay.policy.c_str(), episode->step(), scenario.mission.max_steps,
        episode->NumLocalized(), m, video->frames(), video->frames() / wall);
    progress.Update(buf);
  }
  const cv::Mat& last = emit(*episode);
  const int hold = static_cast<int>(std::lround(options.hold_seconds * fps));
  for (int h = 0; h < hold; ++h) video->Write(last);
  progress.Finish();
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
          .count();
  video->Commit();
  trace.Commit();

  RenderResult r;
  r.mission = Summarize(*episode, wall);
  r.video = options.out_file;
  r.codec = video->codec();
  r.frames = video->frames();
  r.fps = fps;
  r.width = width;
  r.height = height;
  r.video_seconds = static_cast<double>(r.frames) / fps;
  r.frames_per_second = r.frames / wall;
  r.png_frames = png_frames;

  nlohmann::ordered_json j =
      nlohmann::ordered_json::parse(SummaryJson(r.mission, *episode));
  nlohmann::ordered_json v;
  v["file"] = out.filename().string();
  v["codec"] = r.codec;
  v["width"] = width;
  v["height"] = height;
  v["fps"] = fps;
  v["frames"] = r.frames;
  v["held_frames"] = hold;
  v["duration_s"] = r.video_seconds;
  v["sim_seconds"] = sim_time;
  v["heatmap_robot"] = heat_robot;
  v["png_frames"] = png_frames;
  v["frames_per_second"] = r.frames_per_second;
  // Where the wall time went (the mission's own phases are in `aia bench`).
  nlohmann::ordered_json t;
  t["scene"] = renderer.scene_seconds();
  t["overlay"] = renderer.overlay_seconds();
  t["encode"] = write_seconds;
  t["total"] = wall;
  v["seconds"] = t;
  j["video"] = v;
  WriteFileAtomic(summary_path, j.dump(2) + "\n");

  const MissionSummary& s = r.mission;
  std::printf(
      "%s: policy %s, seed %llu: %s in %d steps (%d robots, %d targets, "
      "%ld invalid moves); %d frames at %d fps (%.2f s, %dx%d, %s), "
      "%.1f frames/s -> %s\n",
      scenario.name.c_str(), s.policy.c_str(),
      static_cast<unsigned long long>(s.seed),
      s.success ? "success" : "no success", s.success ? s.flowtime : s.steps,
      s.robots, s.targets, s.invalid_moves, r.frames, fps, r.video_seconds,
      width, height, r.codec.c_str(), r.frames_per_second,
      options.out_file.c_str());
  return r;
}

}  // namespace aia
