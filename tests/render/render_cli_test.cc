// `aia render` end to end: the MP4 has the frames and duration the program
// reports (checked with ffprobe), frames are neither blank nor repeated, the
// mission ends as under `aia run`, and bad input exits with 2.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>
#include <set>

#include "support/test_support.h"

namespace aia {
namespace {

namespace fs = std::filesystem;
using testing::ReadFile;
using testing::RunAia;

// A short mission on a small world: range-limited talk with packet loss and a
// robot that fails at step 2, so every overlay has something to draw.
constexpr const char* kScenario = R"(name: short
seed: 3
workspace:
  size: [8.0, 6.0]
  obstacles:
    boxes: [{center: [4.0, 3.0], size: [0.6, 2.0]}]
robots: {count: 3, start: [[1.25, 1.25], [6.75, 4.75], [1.25, 4.75]]}
targets:
  list:
    - {position: [2.6, 2.1]}
    - {position: [6.2, 1.4]}
mission: {eps: 0.0001, max_steps: 4}
communication: {mode: range, range: 5.0, packet_loss_lambda: 1.0, failures: [{robot: 2, step: 2}]}
policy: {name: greedy}
render: {width: 160, height: 120, fps: 30, follow_robot: 0}
)";

class RenderCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("aia_render_");
    scenario_ = dir_ + "/short.yaml";
    std::ofstream(scenario_) << kScenario;
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string dir_, scenario_;
};

struct Probe {
  int frames = -1, width = -1, height = -1;
  std::string codec, rate;
  double duration = -1.0;
};

Probe FfProbe(const std::string& file) {
  const auto r = testing::RunCommand(
      "ffprobe -v error -select_streams v:0 -count_frames -show_entries "
      "stream=codec_name,width,height,r_frame_rate,nb_read_frames,duration "
      "-of default=noprint_wrappers=1 '" +
      file + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  Probe p;
  std::istringstream in(r.out);
  std::string line;
  while (std::getline(in, line)) {
    const size_t eq = line.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = line.substr(0, eq), value = line.substr(eq + 1);
    if (key == "codec_name") p.codec = value;
    if (key == "width") p.width = std::stoi(value);
    if (key == "height") p.height = std::stoi(value);
    if (key == "r_frame_rate") p.rate = value;
    if (key == "nb_read_frames") p.frames = std::stoi(value);
    if (key == "duration") p.duration = std::stod(value);
  }
  return p;
}

TEST_F(RenderCliTest, VideoHasTheReportedFramesAndDuration) {
  const std::string video = dir_ + "/out/short.mp4";
  const auto r =
      RunAia({"render", scenario_, "--out", video, "--fps", "25", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto summary =
      nlohmann::json::parse(ReadFile(dir_ + "/out/short.summary.json"));
  const auto& v = summary["video"];
  const int frames = v["frames"];
  const int fps = v["fps"];
  ASSERT_EQ(fps, 25);
  // One frame at the start, one per 1/fps s of physics, one after the last
  // step's fusion, then the final frame held one second.
  const double sim_seconds = v["sim_seconds"];
  const int held = v["held_frames"];
  EXPECT_EQ(held, 25);
  EXPECT_EQ(frames, 1 + static_cast<int>(std::floor(sim_seconds * fps + 1e-6)) +
                        1 + held);
  EXPECT_NE(r.out.find(std::to_string(frames) + " frames at 25 fps"),
            std::string::npos)
      << r.out;

  const Probe p = FfProbe(video);
  EXPECT_EQ(p.codec, "h264");
  EXPECT_EQ(p.width, 160);
  EXPECT_EQ(p.height, 120);
  EXPECT_EQ(p.rate, "25/1");
  EXPECT_EQ(p.frames, frames);
  EXPECT_NEAR(p.duration, static_cast<double>(frames) / fps, 0.5 / fps);
  EXPECT_TRUE(fs::exists(dir_ + "/out/short.trace.csv"));
  // The video and the result files of `aia run`, nothing temporary.
  std::set<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir_ + "/out"))
    files.insert(entry.path().filename().string());
  EXPECT_EQ(files, (std::set<std::string>{
                       "short.mp4", "short.summary.json", "short.trace.csv",
                       "short.estimate.csv", "short.effective.yaml",
                       "short.diagnostics.json"}));
}

TEST_F(RenderCliTest, FramesAreNotBlankAndDiffer) {
  const std::string frames_dir = dir_ + "/frames";
  const auto r = RunAia({"render", scenario_, "--out", dir_ + "/v.mp4",
                         "--frames", frames_dir, "--hold", "0", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto summary =
      nlohmann::json::parse(ReadFile(dir_ + "/v.summary.json"));
  const int frames = summary["video"]["frames"];
  ASSERT_EQ(summary["video"]["png_frames"].get<int>(), frames);
  EXPECT_EQ(FfProbe(dir_ + "/v.mp4").frames, frames);

  cv::Mat previous, first;
  int differing = 0;
  for (int f = 0; f < frames; ++f) {
    char name[32];
    std::snprintf(name, sizeof(name), "/frame_%06d.png", f);
    const cv::Mat image = cv::imread(frames_dir + name);
    ASSERT_FALSE(image.empty()) << name;
    ASSERT_EQ(image.cols, 160);
    ASSERT_EQ(image.rows, 120);
    cv::Mat gray;
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
    cv::Scalar mean, stddev;
    cv::meanStdDev(gray, mean, stddev);
    EXPECT_GT(stddev[0], 20.0) << name << " looks blank";
    if (!previous.empty()) {
      cv::Mat diff;
      cv::absdiff(previous, image, diff);
      differing += cv::countNonZero(diff.reshape(1)) > 0 ? 1 : 0;
    } else {
      first = image;
    }
    previous = image;
  }
  // Robots move in every physics frame; allow a still moment or two.
  EXPECT_GE(differing, (frames - 1) * 9 / 10)
      << differing << " of " << frames - 1;
  cv::Mat diff;
  cv::absdiff(first, previous, diff);
  EXPECT_GT(cv::countNonZero(diff.reshape(1) > 30), 200);
}

TEST_F(RenderCliTest, EveryKthFrameAsPng) {
  const std::string frames_dir = dir_ + "/frames";
  const auto r = RunAia({"render", scenario_, "--out", dir_ + "/v.mp4",
                         "--frames", frames_dir, "--frames-every", "10",
                         "--max-steps", "2", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto summary =
      nlohmann::json::parse(ReadFile(dir_ + "/v.summary.json"));
  const int mission_frames = summary["video"]["frames"].get<int>() -
                             summary["video"]["held_frames"].get<int>();
  int pngs = 0;
  for (const auto& entry : fs::directory_iterator(frames_dir)) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(std::regex_match(name, std::regex("frame_[0-9]{6}\\.png")))
        << name;
    EXPECT_EQ(std::stoi(name.substr(6, 6)) % 10, 0) << name;
    ++pngs;
  }
  EXPECT_EQ(pngs, (mission_frames + 9) / 10);
  EXPECT_EQ(summary["steps"].get<int>(), 2);
  // Again into the same folder, shorter: the folder holds this render's
  // frames only (an earlier render's last ones stayed among them).
  std::ofstream(frames_dir + "/frame_999990.png") << "old";
  ASSERT_EQ(RunAia({"render", scenario_, "--out", dir_ + "/v.mp4", "--frames",
                    frames_dir, "--frames-every", "10", "--max-steps", "1",
                    "--quiet"})
                .exit_code,
            0);
  const auto again = nlohmann::json::parse(ReadFile(dir_ + "/v.summary.json"));
  int now = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(frames_dir))
    ++now;
  EXPECT_EQ(now, again["video"]["png_frames"].get<int>());
  EXPECT_FALSE(fs::exists(frames_dir + "/frame_999990.png"));
}

TEST_F(RenderCliTest, EndsLikeAiaRun) {
  const auto run =
      RunAia({"run", scenario_, "--out", dir_ + "/run", "--quiet"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto render =
      RunAia({"render", scenario_, "--out", dir_ + "/r.mp4", "--quiet"});
  ASSERT_EQ(render.exit_code, 0) << render.err;
  const auto a = nlohmann::json::parse(ReadFile(dir_ + "/run/summary.json"));
  const auto b = nlohmann::json::parse(ReadFile(dir_ + "/r.summary.json"));
  for (const char* key : {"success", "flowtime", "steps", "invalid_moves",
                          "final_min_det", "failed_robots"})
    EXPECT_EQ(a[key], b[key]) << key;
  EXPECT_EQ(ReadFile(dir_ + "/run/trace.csv"), ReadFile(dir_ + "/r.trace.csv"));
  // What the video draws does not change the mission.
  const auto none = RunAia({"render", scenario_, "--out", dir_ + "/n.mp4",
                            "--edges", "none", "--quiet"});
  ASSERT_EQ(none.exit_code, 0) << none.err;
  EXPECT_EQ(ReadFile(dir_ + "/run/trace.csv"), ReadFile(dir_ + "/n.trace.csv"));
  const auto c = nlohmann::json::parse(ReadFile(dir_ + "/n.summary.json"));
  EXPECT_EQ(c["video"]["edges"], "none");
  EXPECT_EQ(b["video"]["edges"], "auto");
}

TEST_F(RenderCliTest, PlotScriptDrawsTheTrace) {
  if (testing::RunCommand("/usr/bin/python3 -c 'import matplotlib, numpy'")
          .exit_code != 0)
    GTEST_SKIP() << "Debian's python3-matplotlib is not installed";
  const auto r =
      RunAia({"render", scenario_, "--out", dir_ + "/v.mp4", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string png = dir_ + "/plots/v.png";
  const auto plot =
      testing::RunCommand(testing::SourcePath("tools/plot_trace.py") + " " +
                          dir_ + "/v.trace.csv --out " + png);
  ASSERT_EQ(plot.exit_code, 0) << plot.err;
  const cv::Mat image = cv::imread(png);
  ASSERT_FALSE(image.empty());
  EXPECT_GT(image.cols, 800);
  const auto bad =
      testing::RunCommand(testing::SourcePath("tools/plot_trace.py") + " " +
                          scenario_ + " --out " + dir_ + "/bad.png");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(bad.err.rfind("error: ", 0), 0u) << bad.err;
}

struct BadCase {
  const char* name;
  std::vector<std::string> args;
  std::string flag;
};

TEST_F(RenderCliTest, BadInputExitsWith2) {
  const std::string out = dir_ + "/bad.mp4";
  fs::create_directories(dir_ + "/file_not_dir");
  std::ofstream(dir_ + "/plain_file") << "x";
  const std::vector<BadCase> cases = {
      {"zero width", {"--width", "0"}, "--width"},
      {"odd height", {"--height", "121"}, "--height"},
      {"zero fps", {"--fps", "0"}, "--fps"},
      {"fps above the physics rate", {"--fps", "1000"}, "--fps"},
      {"unknown policy", {"--policy", "nope"}, "--policy"},
      {"heatmap robot out of range", {"--heatmap", "3"}, "--heatmap"},
      {"heatmap below -1", {"--heatmap", "-2"}, "--heatmap"},
      {"zero max steps", {"--max-steps", "0"}, "--max-steps"},
      {"frames every 0",
       {"--frames", dir_ + "/f", "--frames-every", "0"},
       "--frames-every"},
      {"negative hold", {"--hold", "-1"}, "--hold"},
      {"unknown edges", {"--edges", "some"}, "--edges"},
      // It did nothing, silently.
      {"frames every without frames",
       {"--frames-every", "5"},
       "--frames-every"},
  };
  for (const BadCase& c : cases) {
    std::vector<std::string> args = {"render", scenario_, "--out", out,
                                     "--quiet"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const auto r = RunAia(args);
    EXPECT_EQ(r.exit_code, 2) << c.name << ": " << r.err;
    EXPECT_EQ(r.err.rfind("error: command line: " + c.flag + ": ", 0), 0u)
        << c.name << ": " << r.err;
  }
  const std::vector<BadCase> paths = {
      {"not an mp4", {"--out", dir_ + "/video.avi"}, "--out"},
      {"directory under a file",
       {"--out", dir_ + "/plain_file/sub/v.mp4"},
       "--out"},
      {"frames under a file",
       {"--out", out, "--frames", dir_ + "/plain_file/f"},
       "--frames"},
      // Refused before the folder was made (it then blocked the corrected
      // command: "--out ... is a folder").
      {"frames in the video's place",
       {"--out", dir_ + "/fl/v.mp4", "--frames", dir_ + "/fl/./v.mp4"},
       "--frames"},
      // Files are written as NAME.tmp.PID first: a name the file system
      // takes could fail only there, after the whole mission.
      {"a name too long for its temporary form",
       {"--out", dir_ + "/" + std::string(240, 'a') + ".mp4"},
       "--out"},
  };
  for (const BadCase& c : paths) {
    std::vector<std::string> args = {"render", scenario_, "--quiet"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const auto r = RunAia(args);
    EXPECT_EQ(r.exit_code, 2) << c.name << ": " << r.err;
    EXPECT_EQ(r.err.rfind("error: command line: " + c.flag + ": ", 0), 0u)
        << c.name << ": " << r.err;
  }
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(dir_ + "/fl"));
  // A bad render section in the file names the file, line and key.
  std::string odd = kScenario;
  odd.replace(odd.find("width: 160"), 10, "width: 161");
  std::ofstream(dir_ + "/odd.yaml") << odd;
  const auto r =
      RunAia({"render", dir_ + "/odd.yaml", "--out", out, "--quiet"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(
      r.err.rfind(
          "error: " + dir_ + "/odd.yaml:15: render.width: must be an even", 0),
      0u)
      << r.err;
}

// Issue 19: a full disk printed libpng's own message for PNG frames, and a
// cut video was renamed into place as if whole.
TEST_F(RenderCliTest, FullDiskGivesOneClearError) {
  const testing::SmallDisk disk("32k");
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here";
  const auto expect_no_space = [](const testing::CommandResult& r,
                                  const std::string& file) {
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_EQ(r.err,
              "error: cannot write '" + file + "': No space left on device\n");
  };
  auto r = RunAia({"render", scenario_, "--out", dir_ + "/v.mp4", "--frames",
                   disk.dir() + "/f", "--quiet"});
  expect_no_space(r, disk.dir() + "/f/frame_000001.png");
  fs::remove_all(disk.dir() + "/f");
  r = RunAia({"render", scenario_, "--out", disk.dir() + "/v.mp4", "--width",
              "320", "--height", "240", "--hold", "10", "--quiet"});
  expect_no_space(r, disk.dir() + "/v.mp4");
  EXPECT_FALSE(fs::exists(disk.dir() + "/v.mp4"));
  EXPECT_TRUE(testing::Temporaries(disk.dir()).empty());
}

// Issue 19: Ctrl-C ended a render without its summary and left the partial
// video. Now it ends like `aia run`: after the current step, the video so
// far finished, the summary marked, exit 130; what killed renders leave is
// removed by the next render into the folder.
TEST_F(RenderCliTest, CtrlCFinishesTheVideoSoFarAndStaleFilesAreRemoved) {
  const std::string out = dir_ + "/int";
  fs::create_directories(out);
  const std::string render =
      "'" + std::string(AIA_BINARY) + "' render '" +
      testing::SourcePath("scenarios/default.yaml") +
      "' --policy random --max-steps 1000000 --set "
      "mission.stop_at_success=false --width 64 --height 48 --out '" +
      out + "/v.mp4' --quiet";
  // Once the mission runs (its trace is open), a signal; then the exit code.
  const auto send = [&](const std::string& name) {
    const std::string script =
        render + " & pid=$!\nfor i in $(seq 600); do ls -a '" + out +
        "' | grep -q 'trace.csv.tmp' && break; sleep 0.05; done\nsleep 1\n"
        "kill -" +
        name + " $pid; wait $pid; echo rc=$?\n";
    return testing::RunCommand(
        "bash -c '" + std::regex_replace(script, std::regex("'"), "'\\''") +
        "'");
  };
  auto r = send("INT");
  EXPECT_NE(r.out.find("rc=130"), std::string::npos) << r.out << r.err;
  const auto summary = nlohmann::json::parse(ReadFile(out + "/v.summary.json"));
  EXPECT_EQ(summary["interrupted"], true);
  const int frames = summary["video"]["frames"];
  EXPECT_GT(frames, 1);
  EXPECT_EQ(FfProbe(out + "/v.mp4").frames, frames);
  EXPECT_TRUE(testing::Temporaries(out).empty());

  // SIGKILL leaves the partial video and the result files' temporaries;
  // the next render into the folder removes them (their process is gone).
  r = send("KILL");
  EXPECT_NE(r.out.find("rc=137"), std::string::npos) << r.out << r.err;
  EXPECT_FALSE(testing::Temporaries(out).empty());
  bool partial_video = false;
  for (const std::string& t : testing::Temporaries(out))
    partial_video |=
        std::regex_search(t, std::regex("/\\.v\\.tmp\\.[0-9]+\\.mp4$"));
  EXPECT_TRUE(partial_video);
  r = RunAia({"render", scenario_, "--out", out + "/other.mp4", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(testing::Temporaries(out).empty());
}

TEST(RenderCliHelpTest, HelpNamesTheFlags) {
  const auto r = RunAia({"render", "--help"});
  EXPECT_EQ(r.exit_code, 0);
  for (const char* flag :
       {"--out", "--policy", "--seed", "--width", "--height", "--fps",
        "--frames", "--heatmap", "--max-steps", "--edges", "--quiet"})
    EXPECT_NE(r.out.find(flag), std::string::npos) << flag;
}

}  // namespace
}  // namespace aia
