#include "aia/commands/render_mission.h"

#include <sys/resource.h>

#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "aia/commands/episode_picture.h"
#include "aia/core/clock.h"
#include "aia/core/error.h"
#include "aia/core/interrupt.h"
#include "aia/core/io.h"
#include "aia/estimation/heatmap.h"
#include "aia/render/frame_renderer.h"
#include "aia/render/video.h"
#include "aia/runtime/outputs.h"
#include "aia/scenario/loader.h"
#include "aia/world/media.h"

namespace aia {

EpisodePicture::EpisodePicture(const Episode& e, FrameRenderer* renderer)
    : renderer_(renderer) {
  const Scenario& s = e.scenario();
  heat_robot_ = s.render.follow_robot;
  heat_params_.eps = e.mission().eps;
  heat_params_.blur = 0.5 * s.sensor.range;
  if (heat_robot_ >= 0)
    heat_ =
        MakeHeatmapGrid(e.world().map.size(), e.world().map.occupancy().cell());
  overlay_.max_steps = e.mission().max_steps;
  overlay_.policy = std::string(e.policy().name());
  overlay_.seed = s.seed;
  overlay_.eps = e.mission().eps;
  overlay_.sensor_range = s.sensor.range;
  overlay_.neighbors = &e.comm().AllNeighbors();
  overlay_.lost = &e.comm().Lost();
  overlay_.heatmap_robot = heat_robot_;
}

void EpisodePicture::AfterStep(const Episode& e) {
  const int m = e.world().NumTargets();
  const double eps = e.mission().eps;
  overlay_.targets.resize(m);
  for (int k = 0; k < m; ++k) {
    // The team's best estimate; every robot failed: robot 0's belief.
    const int best = std::max(0, e.BestRobot(k));
    TargetOverlay& t = overlay_.targets[k];
    t.mean = e.beliefs().PositionMean(best, k);
    t.cov = e.beliefs().PositionCovariance(best, k);
    t.det = e.Det(best, k);
    t.weight = HeatWeight(e.beliefs().LogDetCovariance(best, k),
                          e.log_det_prior()[k], eps);
  }
  overlay_.step = e.step();
  overlay_.localized = e.NumLocalized();
  renderer_->AddTrailPoints(e.robot_positions());
  if (heat_robot_ >= 0) {
    ProjectHeatmap(e.beliefs(), heat_robot_, e.log_det_prior(), heat_params_,
                   &heat_);
    renderer_->SetHeatmap(&heat_);
  }
}

const cv::Mat& EpisodePicture::Render(const Episode& e) {
  const Simulation& sim = e.sim();
  overlay_.seconds = e.clock_seconds();
  overlay_.robots.resize(sim.num_robots());
  for (int i = 0; i < sim.num_robots(); ++i)
    overlay_.robots[i] = sim.RobotPosition(i);
  overlay_.headings.clear();
  if (sim.robot_model() == RobotModel::kDiffDrive) {
    for (int i = 0; i < sim.num_robots(); ++i)
      overlay_.headings.push_back(sim.RobotHeading(i));
  }
  for (int k = 0; k < sim.num_targets(); ++k)
    overlay_.targets[k].truth = sim.TargetPosition(k);
  overlay_.active = e.comm().active();
  return renderer_->Render(overlay_);
}

namespace {

namespace fs = std::filesystem;

constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;

// The render flags as overrides of the scenario's render section, so that
// they are checked (and reported under the flag) like the file's values.
std::vector<Override> RenderOverrides(const RenderOptions& o,
                                      const PolicyRegistry& registry) {
  std::vector<Override> out = o.overrides.ToOverrides(registry);
  const auto add = [&out](const char* flag, const char* path,
                          const std::optional<int>& v) {
    if (v) out.push_back({flag, path, std::to_string(*v)});
  };
  add("--width", "render.width", o.width);
  add("--height", "render.height", o.height);
  add("--fps", "render.fps", o.fps);
  add("--heatmap", "render.follow_robot", o.heatmap_robot);
  return out;
}

// The render section's flags and what its size needs (its even sides and
// frame rate are checked wherever a scenario is read: RenderConfig).
void CheckRenderSection(const Scenario& s, const RenderOptions& o) {
  {
    RenderOptions flags = o;
    CheckFlags(&flags);  // their declarations: `--flag: what`
  }
  // What the size needs, against the budget, before any work (an 8192 x
  // 8192 video took 12 to 15 GB).
  const double need = RenderMemoryNeed(s.render.width, s.render.height);
  const double budget = o.memory_budget * kGiB;
  if (need > budget) {
    char what[320];
    std::snprintf(what, sizeof what,
                  "%d x %d pixels need about %.2f GiB (512 MiB + 256 bytes "
                  "per pixel), more than the render's memory budget of %s "
                  "GiB (--memory-budget); a smaller size, or a larger budget "
                  "on a machine that has it",
                  s.render.width, s.render.height, need / kGiB,
                  FormatNumber(o.memory_budget).c_str());
    throw s.ErrorAt("render.width", what);
  }
  // A process limit below the need (ulimit -v) would end the encoder
  // midway; it is a budget too.
  struct rlimit limit;
  if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY &&
      need > static_cast<double>(limit.rlim_cur)) {
    char what[320];
    std::snprintf(what, sizeof what,
                  "%d x %d pixels need about %.2f GiB (512 MiB + 256 bytes "
                  "per pixel), more than this process may take (%.2f GiB, "
                  "ulimit -v); a smaller size",
                  s.render.width, s.render.height, need / kGiB,
                  static_cast<double>(limit.rlim_cur) / kGiB);
    throw s.ErrorAt("render.width", what);
  }
}

// Films the episode: a frame every 1/fps seconds of simulated time, taken
// from the physics substeps, with the overlays of the last completed step.
class VideoObserver : public StepObserver {
 public:
  VideoObserver(const Episode& e, const RenderOptions& options,
                FrameRenderer* renderer, Mp4Writer* video)
      : options_(options), picture_(e, renderer), video_(video) {
    fps_ = e.scenario().render.fps;
    frame_dt_ = 1.0 / fps_;
    next_frame_ = frame_dt_;
  }

  void OnStart(const Episode& e) override {
    picture_.AfterStep(e);
    Emit(e);
  }
  ObserverStatus OnDecision(const Episode&, const DecisionContext&,
                            const Decision&) override {
    step_start_ = sim_time_;
    return ObserverStatus::kContinue;
  }
  void OnSubstep(const Episode& e, double elapsed) override {
    sim_time_ = step_start_ + elapsed;
    if (sim_time_ + 1e-9 >= next_frame_) {
      Emit(e);
      next_frame_ += frame_dt_;
    }
  }
  ObserverStatus OnStep(const Episode& e) override {
    picture_.AfterStep(e);
    return ObserverStatus::kContinue;
  }
  // The state after the last step's fusion, held `hold` seconds; Ctrl-C
  // cuts the hold short (the video is then not whole: the summary says
  // interrupted).
  void OnEnd(const Episode& e) override {
    const cv::Mat& last = Emit(e);
    const int hold = static_cast<int>(std::lround(options_.hold * fps_));
    for (held_ = 0; held_ < hold; ++held_) {
      if (Interrupted()) {
        hold_cut_ = true;
        break;
      }
      video_->Write(last);
    }
  }

  int png_frames() const { return png_frames_; }
  int held() const { return held_; }
  bool hold_cut() const { return hold_cut_; }
  double sim_time() const { return sim_time_; }
  double write_seconds() const { return write_seconds_; }

 private:
  const cv::Mat& Emit(const Episode& e) {
    const cv::Mat& image = picture_.Render(e);
    const auto t_write = std::chrono::steady_clock::now();
    if (!options_.frames_dir.empty() &&
        video_->frames() % options_.frames_every == 0) {
      char name[32];
      std::snprintf(name, sizeof(name), "frame_%06d.png", video_->frames());
      const std::string path = (fs::path(options_.frames_dir) / name).string();
      // Encoded in memory and written by aia's atomic writer: a failed write
      // (a full disk) is "cannot write 'PATH': <errno text>", where
      // cv::imwrite prints libpng's own message and returns false.
      const std::string png =
          EncodePng(image.data, image.cols, image.rows, image.step);
      if (png.empty()) ThrowCannotWrite(path, "the PNG encoder failed");
      WriteFileAtomic(path, png);
      ++png_frames_;
    }
    video_->Write(image);
    write_seconds_ += SecondsSince(t_write);
    return image;
  }

  const RenderOptions& options_;
  EpisodePicture picture_;
  Mp4Writer* video_;
  int fps_ = 30;
  double frame_dt_ = 1.0 / 30, next_frame_ = 1.0 / 30;
  double sim_time_ = 0.0, step_start_ = 0.0;
  int png_frames_ = 0, held_ = 0;
  bool hold_cut_ = false;
  double write_seconds_ = 0.0;  // H.264 encoding and PNG files
};

}  // namespace

namespace {

// The PNG frames to be written into --frames: one that is there already as
// a FIFO, device or folder is refused now, not after the rendering.
// The frame_NNNNNN.png files in `dir` (none when it is not a folder).
std::vector<std::string> FrameFiles(const std::string& dir) {
  std::error_code ec;
  std::vector<std::string> frames;
  if (dir.empty() || !fs::is_directory(dir, ec)) return frames;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() == 16 && name.rfind("frame_", 0) == 0 &&
        name.compare(12, 4, ".png") == 0)
      frames.push_back(it->path().string());
  }
  return frames;
}

void CheckFrameFiles(const std::string& dir) {
  CheckOutputFiles(FrameFiles(dir), "--frames", "a frame");
}

// Neither the video nor the files next to it may replace an input (the
// scenario may be FILE.effective.yaml of an earlier render); the folders
// are made. The folder is not locked (renders of other scenarios may share
// it), but what killed renders left there (a partial video, temporaries of
// their result files) is removed: only files whose process is gone.
void PrepareOutputs(const RenderOptions& options,
                    const PreparedMission& mission, const std::string& prefix) {
  const fs::path out(options.out_file);
  const std::vector<InputFile> inputs =
      MissionInputs(mission.scenario, mission.policy.get());
  CheckNotAnInput(options.out_file, "--out", inputs);
  for (const std::string& name : MissionFileNames())
    CheckNotAnInput(prefix + name, "--out", inputs,
                    "written next to the video");
  MakeOutputDir(out.parent_path().string(), "--out");
  MakeOutputDir(options.frames_dir, "--frames");
  // The folder's frames are this render's: an earlier render's (a longer
  // one's frames past this one's last) would sit among them.
  for (const std::string& old : FrameFiles(options.frames_dir)) {
    std::error_code ec;
    fs::remove(old, ec);
  }
  RemoveStaleTemporaries(
      out.parent_path().empty() ? "." : out.parent_path().string());
  if (!options.frames_dir.empty()) RemoveStaleTemporaries(options.frames_dir);
}

// --out: an .mp4 file that may be written, and the files next to it
// (FILE.summary.json, ...) and the PNG frames of --frames that may be
// written too. Returns the prefix of the files next to it ("DIR/NAME.").
std::string CheckVideoPaths(const RenderOptions& options) {
  const fs::path out(options.out_file);
  if (options.out_file.empty() || out.extension() != ".mp4" ||
      out.stem().empty())
    throw InputError::Flag(
        "--out", "must name an .mp4 file, got '" + options.out_file + "'");
  CheckOutputFile(options.out_file, "--out");
  // The frames' folder cannot be the video, nor a file written next to it
  // (found before any folder is made).
  if (!options.frames_dir.empty() &&
      fs::path(options.frames_dir).lexically_normal() == out.lexically_normal())
    throw InputError::Flag("--frames",
                           "'" + options.frames_dir +
                               "' is the video's own path (--out); give the "
                               "frames a folder of their own");
  if (options.frames_dir.empty() && options.frames_every != 1)
    throw InputError::Flag("--frames-every",
                           "needs --frames (the folder of the PNG frames)");
  const std::string prefix =
      (out.parent_path() / (out.stem().string() + ".")).string();
  std::vector<std::string> next_to_it;
  for (const std::string& name : MissionFileNames())
    next_to_it.push_back(prefix + name);
  CheckOutputFiles(next_to_it, "--out", "written next to the video");
  CheckFrameFiles(options.frames_dir);
  return prefix;
}

// The video section of FILE.summary.json: the file, its frames, and where
// the wall time went.
nlohmann::ordered_json VideoSection(const RenderResult& r,
                                    const Scenario& scenario,
                                    const FrameRenderer& renderer,
                                    const VideoObserver& filming,
                                    EdgeMode edges, double wall) {
  nlohmann::ordered_json v;
  v["file"] = fs::path(r.video).filename().string();
  v["codec"] = r.codec;
  v["width"] = r.width;
  v["height"] = r.height;
  v["fps"] = r.fps;
  v["frames"] = r.frames;
  v["held_frames"] = filming.held();
  v["duration_s"] = r.video_seconds;
  v["sim_seconds"] = filming.sim_time();
  v["heatmap_robot"] = scenario.render.follow_robot;
  v["png_frames"] = r.png_frames;
  v["frames_per_second"] = r.frames_per_second;
  // The video's own cost: frames per second of scene, overlay and encoder
  // time, without the mission's.
  const double video_seconds = renderer.scene_seconds() +
                               renderer.overlay_seconds() +
                               filming.write_seconds();
  v["render_frames_per_second"] =
      video_seconds > 0.0 ? r.frames / video_seconds : 0.0;
  v["edges"] = EnumNameOf(edges);
  v["compact"] = renderer.compact();
  // Where the wall time went (the mission's own phases are in
  // diagnostics.json and `aia bench`); mission: the rest (start-up, policy,
  // physics, fusion, result files).
  nlohmann::ordered_json t;
  t["scene"] = renderer.scene_seconds();
  t["overlay"] = renderer.overlay_seconds();
  t["encode"] = filming.write_seconds();
  t["mission"] = std::max(0.0, wall - video_seconds);
  t["total"] = wall;
  v["seconds"] = t;
  return v;
}

// The command's one line.
void PrintRendered(const std::string& scenario, const RenderResult& r) {
  const MissionSummary& s = r.mission;
  std::printf(
      "%s: policy %s, seed %llu: %s in %d steps (%d robots, %d targets, "
      "%ld invalid moves); %d frames at %d fps (%.2f s, %dx%d, %s), "
      "%.1f frames/s -> %s\n",
      scenario.c_str(), s.policy.c_str(),
      static_cast<unsigned long long>(s.seed),
      s.success ? "success" : "no success", s.success ? s.flowtime : s.steps,
      s.robots, s.targets, s.invalid_moves, r.frames, r.fps, r.video_seconds,
      r.width, r.height, r.codec.c_str(), r.frames_per_second, r.video.c_str());
}

}  // namespace

double RenderMemoryNeed(int width, int height) {
  return 512.0 * 1024 * 1024 +
         256.0 * static_cast<double>(width) * static_cast<double>(height);
}

RenderResult RenderMission(const RenderOptions& options) {
  const PolicyRegistry registry = AllPolicies();
  Scenario scenario =
      LoadScenario(options.scenario_path, RenderOverrides(options, registry));
  CheckRenderSection(scenario, options);
  const std::string prefix = CheckVideoPaths(options);
  const PreparedMission mission = PrepareMission(scenario, registry);
  PrepareOutputs(options, mission, prefix);
  const int fps = scenario.render.fps;
  const int width = scenario.render.width, height = scenario.render.height;

  // The video first: opening it loads the codecs (world/media.h), which
  // is done before the mission's files appear.
  std::unique_ptr<Mp4Writer> video;
  const auto started = std::chrono::steady_clock::now();
  try {
    video = std::make_unique<Mp4Writer>(options.out_file, width, height, fps);
  } catch (const std::runtime_error& e) {
    throw InputError::Flag("--out", e.what());
  }
  MissionRunner runner(mission, prefix, "aia render", options.progress, [&] {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "frame %d  %.1f fps",
                  video ? video->frames() : 0,
                  video ? video->frames() / SecondsSince(started) : 0.0);
    return std::string(buf);
  });
  FrameSettings settings;
  settings.scene.width = width;
  settings.scene.height = height;
  settings.edges = options.edges;
  FrameRenderer renderer(runner.episode().sim(), mission.instance->world.map,
                         settings);
  VideoObserver filming(runner.episode(), options, &renderer, video.get());
  runner.AddObserver(&filming);
  const MissionSummary summary = runner.Run();
  video->Commit();
  const double wall = SecondsSince(started);

  RenderResult r;
  r.mission = summary;
  r.video = options.out_file;
  r.codec = video->codec();
  r.frames = video->frames();
  r.fps = fps;
  r.width = width;
  r.height = height;
  r.video_seconds = static_cast<double>(r.frames) / fps;
  r.frames_per_second = r.frames / wall;
  r.png_frames = filming.png_frames();

  nlohmann::ordered_json j =
      nlohmann::ordered_json::parse(SummaryJson(summary, runner.episode()));
  if (filming.hold_cut()) j["interrupted"] = true;
  j["video"] =
      VideoSection(r, scenario, renderer, filming, settings.edges, wall);
  WriteFileAtomic(
      prefix + "summary.json",
      j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
  PrintRendered(scenario.name, r);
  return r;
}

}  // namespace aia
