#include "aia/world/world.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <new>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "aia/core/check.h"
#include "aia/core/error.h"
#include "aia/core/io.h"
#include "aia/core/rng.h"
#include "aia/world/generator.h"
#include "aia/world/map.h"
#include "aia/world/media.h"
#include "aia/world/mjcf.h"

namespace aia {
namespace {

std::string Fmt(const Vec2& v) {
  std::ostringstream os;
  os << "[" << v.x() << ", " << v.y() << "]";
  return os.str();
}

[[noreturn]] void Fail(const Scenario& s, const std::string& key,
                       const std::string& what) {
  throw s.ErrorAt(key, what);
}

// Random boxes keep clear of the robot starts and targets the scenario places
// by hand: a box that comes within `keep_out` of one is drawn again (the draws
// of a scenario that places nothing, or whose boxes stay clear, are unchanged).
std::vector<Box> RandomBoxes(const Scenario& s, Rng& rng) {
  const RandomObstaclesConfig& r = *s.workspace.obstacles.random;
  const Vec2& ws = s.workspace.size;
  std::vector<Vec2> placed(s.robots.start.begin(), s.robots.start.end());
  for (const TargetConfig& t : s.targets.list) placed.push_back(t.position);
  // The robot disc plus one lattice step: the start snaps to a free lattice
  // point, and a target keeps a free point beside it to be seen from.
  const double keep_out = s.robots.radius + s.robots.step;
  auto clear = [&](const Box& b) {
    for (const Vec2& p : placed)
      if (PointBoxDistanceSq(p, b) < keep_out * keep_out) return false;
    return true;
  };
  constexpr int kAttempts = 1000;
  std::vector<Box> boxes;
  boxes.reserve(r.count);
  for (int i = 0; i < r.count; ++i) {
    for (int attempt = 0;; ++attempt) {
      if (attempt == kAttempts)
        Fail(s, "workspace.obstacles.random",
             "cannot place random box " + std::to_string(i) +
                 " clear of the "
                 "placed robot starts and targets (" +
                 std::to_string(kAttempts) +
                 " tries): fewer or smaller boxes, or a larger workspace");
      const Vec2 size(rng.Uniform(r.min_size.x(), r.max_size.x()),
                      rng.Uniform(r.min_size.y(), r.max_size.y()));
      const Vec2 lo(rng.Uniform(0.0, std::max(0.0, ws.x() - size.x())),
                    rng.Uniform(0.0, std::max(0.0, ws.y() - size.y())));
      const Box box{lo, lo + size};
      if (!clear(box)) continue;
      boxes.push_back(box);
      break;
    }
  }
  return boxes;
}

std::vector<Box> MapBoxes(const Scenario& s) {
  const std::string key = "workspace.obstacles.map";
  const std::string& map = s.workspace.obstacles.map;
  // A PNG of kMaxMapPixels pixels is far smaller than this.
  constexpr std::uintmax_t kMaxFileBytes = 256u << 20;
  std::string bytes;
  try {
    bytes = ReadFile(map, kMaxFileBytes);
  } catch (const std::bad_alloc&) {
    throw;  // out of memory is not bad input (cli.cc says it)
  } catch (const std::exception& e) {
    Fail(s, key, e.what());
  }
  GrayImage img;
  try {
    img = DecodeMapImage(bytes);
  } catch (const std::invalid_argument& e) {
    Fail(s, key, "cannot decode image '" + map + "': " + e.what());
  }
  std::vector<Box> boxes =
      BoxesFromImage(img.pixels, img.cols, img.rows, s.workspace.size,
                     s.workspace.obstacles.map_threshold, kMaxBodies);
  if (boxes.size() > static_cast<std::size_t>(kMaxBodies))
    Fail(s, key,
         "the map's dark pixels make more than " + std::to_string(kMaxBodies) +
             " boxes; aia simulates at most " + std::to_string(kMaxBodies) +
             " bodies (a simpler or smaller image)");
  return boxes;
}

// Silences file descriptor 2 while it lives (decoders that print).
class QuietStderr {
 public:
  QuietStderr() : lock_(Mutex()) {
    std::fflush(stderr);
    saved_ = ::dup(2);
    const int null = ::open("/dev/null", O_WRONLY);
    if (saved_ >= 0 && null >= 0) ::dup2(null, 2);
    if (null >= 0) ::close(null);
  }
  ~QuietStderr() {
    if (saved_ < 0) return;
    ::dup2(saved_, 2);
    ::close(saved_);
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  static std::mutex& Mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  int saved_ = -1;
};

// Past whitespace and comments from `*at` (netpbm reads a '#' to the line's
// end anywhere in a PGM's header, and in a plain PGM's numbers).
void SkipPgmSpace(const std::string& b, std::size_t* at) {
  while (*at < b.size()) {
    if (std::isspace(static_cast<unsigned char>(b[*at]))) {
      ++*at;
    } else if (b[*at] == '#') {
      while (*at < b.size() && b[*at] != '\n') ++*at;
    } else {
      break;
    }
  }
}

// Width and height as the image's header declares them, and a PGM's
// maximum grey value (0 for a PNG, or when the header is cut before it) and
// where its pixels begin (after the one whitespace that ends the header);
// false when the bytes are neither PNG nor PGM.
bool HeaderSize(const std::string& b, long long* cols, long long* rows,
                long long* max_gray, std::size_t* data_at) {
  *max_gray = 0;
  static const char kPng[] = "\x89PNG\r\n\x1a\n";
  if (b.size() >= 24 && b.compare(0, 8, kPng, 8) == 0 &&
      b.compare(12, 4, "IHDR") == 0) {
    auto be32 = [&](std::size_t at) {
      long long v = 0;
      for (std::size_t i = 0; i < 4; ++i)
        v = (v << 8) | static_cast<unsigned char>(b[at + i]);
      return v;
    };
    *cols = be32(16);
    *rows = be32(20);
    return true;
  }
  if (b.size() >= 2 && b[0] == 'P' && (b[1] == '2' || b[1] == '5')) {
    std::size_t at = 2;
    long long v[3] = {-1, -1, 0};
    for (long long& x : v) {
      SkipPgmSpace(b, &at);
      std::size_t digits = 0;
      x = 0;
      while (at < b.size() && std::isdigit(static_cast<unsigned char>(b[at])) &&
             digits < 12) {
        x = 10 * x + (b[at++] - '0');
        ++digits;
      }
      if (digits == 0 || digits == 12) {
        if (&x == &v[2]) break;  // the decoder says what is wrong
        return false;
      }
    }
    *cols = v[0];
    *rows = v[1];
    *max_gray = v[2];
    *data_at = at + 1;
    return true;
  }
  return false;
}

}  // namespace

// A PGM whose maximum grey is 256 to 65534: OpenCV reads its 16-bit
// samples as if 65535 were white (a map of 1000 for white came out dark),
// so they are read here, each scaled as the narrow forms are,
// 255 x value / maximum rounded down. Binary (P5): two bytes a sample,
// most significant first; text (P2): decimal numbers.
GrayImage DecodeWidePgm(const std::string& b, int cols, int rows,
                        long long max_gray, std::size_t at) {
  GrayImage out;
  out.cols = cols;
  out.rows = rows;
  const std::size_t n = static_cast<std::size_t>(cols) * rows;
  out.pixels.resize(n);
  const auto put = [&](std::size_t k, long long v) {
    if (v > max_gray)
      throw std::invalid_argument(
          "pixel " + std::to_string(k) + " is " + std::to_string(v) +
          ", above the header's maximum grey " + std::to_string(max_gray));
    out.pixels[k] = static_cast<std::uint8_t>(255LL * v / max_gray);
  };
  if (b[1] == '5') {
    if (at > b.size() || b.size() - at < 2 * n)
      throw std::invalid_argument("the image data is corrupt or truncated");
    for (std::size_t k = 0; k < n; ++k)
      put(k, (static_cast<unsigned char>(b[at + 2 * k]) << 8) |
                 static_cast<unsigned char>(b[at + 2 * k + 1]));
    return out;
  }
  for (std::size_t k = 0; k < n; ++k) {
    SkipPgmSpace(b, &at);
    long long v = 0;
    int digits = 0;
    while (at < b.size() && std::isdigit(static_cast<unsigned char>(b[at])) &&
           digits < 6) {
      v = 10 * v + (b[at++] - '0');
      ++digits;
    }
    if (digits == 0 || digits == 6)
      throw std::invalid_argument("the image data is corrupt or truncated");
    put(k, v);
  }
  return out;
}

GrayImage DecodeMapImage(const std::string& bytes) {
  long long cols = 0, rows = 0, max_gray = 0;
  std::size_t data_at = 0;
  if (!HeaderSize(bytes, &cols, &rows, &max_gray, &data_at))
    throw std::invalid_argument("not a PGM or PNG image");
  if (cols <= 0 || rows <= 0)
    throw std::invalid_argument("the header declares an empty image (" +
                                std::to_string(cols) + " x " +
                                std::to_string(rows) + " pixels)");
  if (cols > kMaxMapPixels || rows > kMaxMapPixels ||
      cols * rows > kMaxMapPixels)
    throw std::invalid_argument(
        "the header declares " + std::to_string(cols) + " x " +
        std::to_string(rows) + " pixels; at most " +
        std::to_string(kMaxMapPixels) + " pixels (e.g. 4096 x 4096)");
  const bool pgm = bytes[0] == 'P';
  if (pgm && data_at <= bytes.size() && (max_gray < 1 || max_gray > 65535))
    throw std::invalid_argument("the header declares a maximum grey of " +
                                std::to_string(max_gray) +
                                "; a PGM's is 1 to 65535");
  if (pgm && max_gray > 255 && max_gray < 65535)
    return DecodeWidePgm(bytes, static_cast<int>(cols), static_cast<int>(rows),
                         max_gray, data_at);
  GrayImage out;
  bool decoded = false;
  {
    // libpng prints its own complaint about a corrupt file to stderr; the
    // reason reaches the user as one error line instead.
    const QuietStderr quiet;
    decoded = DecodeGray(bytes, &out.cols, &out.rows, &out.pixels);
  }
  if (!decoded || out.cols != cols || out.rows != rows)
    throw std::invalid_argument("the image data is corrupt or truncated");
  // A binary PGM whose white is below 255 (P5, maxval 1 to 254) is decoded
  // as stored, so that its white read as grey: white is the file's maximum
  // grey, scaled as the decoder scales the text form (P2), rounding down.
  if (bytes[1] == '5' && max_gray > 0 && max_gray < 255) {
    for (std::uint8_t& p : out.pixels)
      p = static_cast<std::uint8_t>(std::min(255LL, 255LL * p / max_gray));
  }
  return out;
}

std::vector<Box> BoxesFromImage(const std::vector<std::uint8_t>& gray, int cols,
                                int rows, const Vec2& size, double threshold,
                                std::size_t max_boxes) {
  AIA_CHECK(cols >= 0 && rows >= 0 &&
            gray.size() == static_cast<std::size_t>(cols) * rows);
  const double px = size.x() / cols, py = size.y() / rows;
  const double cut = threshold * 255.0;
  // Runs of dark pixels per row, merged downwards while the next row has the
  // exact same run: few boxes for typical maps, exact coverage always. Runs
  // of a row are disjoint and ordered by x0, and so are the open boxes: one
  // merge pass per row.
  struct Run {
    int x0, x1, y0, y1;  // pixel columns [x0, x1), rows [y0, y1)
  };
  std::vector<Run> open, next, done;
  std::vector<std::pair<int, int>> runs;
  for (int r = 0; r <= rows; ++r) {
    runs.clear();
    if (r < rows) {
      const std::uint8_t* row = gray.data() + static_cast<size_t>(r) * cols;
      for (int c = 0; c < cols;) {
        if (row[c] < cut) {
          int e = c;
          while (e < cols && row[e] < cut) ++e;
          runs.push_back({c, e});
          c = e;
        } else {
          ++c;
        }
      }
    }
    next.clear();
    std::size_t i = 0;
    for (const Run& o : open) {
      while (i < runs.size() && runs[i].first < o.x0)
        next.push_back({runs[i].first, runs[i].second, r, r + 1}), ++i;
      if (i < runs.size() && runs[i].first == o.x0 && runs[i].second == o.x1) {
        next.push_back({o.x0, o.x1, o.y0, r + 1});
        ++i;
      } else {
        done.push_back(o);
      }
    }
    for (; i < runs.size(); ++i)
      next.push_back({runs[i].first, runs[i].second, r, r + 1});
    open.swap(next);
    if (done.size() + open.size() > max_boxes) {  // known to be too many
      done.insert(done.end(), open.begin(), open.end());
      break;
    }
  }
  std::vector<Box> boxes;
  boxes.reserve(done.size());
  for (const Run& d : done) {
    // Image row 0 is the top of the map.
    boxes.push_back({Vec2(d.x0 * px, size.y() - d.y1 * py),
                     Vec2(d.x1 * px, size.y() - d.y0 * py)});
  }
  std::sort(boxes.begin(), boxes.end(), [](const Box& a, const Box& b) {
    return std::make_pair(a.lo.y(), a.lo.x()) <
           std::make_pair(b.lo.y(), b.lo.x());
  });
  return boxes;
}

namespace {

// A generated world (alone), or random boxes, then explicit boxes, then the
// map image's; *generated holds what the generator made.
std::vector<Box> AllObstacles(const Scenario& s,
                              std::optional<GeneratedObstacles>* generated) {
  std::vector<Box> obstacles;
  if (s.workspace.obstacles.generator) {
    *generated = GenerateObstacles(s);
    obstacles = (*generated)->boxes;
  }
  if (s.workspace.obstacles.random) {
    Rng rng(s.seed, "obstacles");
    const auto boxes = RandomBoxes(s, rng);
    obstacles.insert(obstacles.end(), boxes.begin(), boxes.end());
  }
  for (const BoxConfig& b : s.workspace.obstacles.boxes)
    obstacles.push_back(Box::FromCenterSize(b.center, b.size));
  if (!s.workspace.obstacles.map.empty()) {
    const auto boxes = MapBoxes(s);
    obstacles.insert(obstacles.end(), boxes.begin(), boxes.end());
  }
  return obstacles;
}

// The given starts, each checked (outside every obstacle, snapping to a free
// lattice point of its own), or random distinct free points of the largest
// connected component, so that every robot can reach every other robot's
// region.
// Headings at the start (radians from +x): a point robot has none (0); a
// diff_drive robot robots.diff_drive.start_heading, or one drawn per robot
// from its own stream.
std::vector<double> StartHeadings(const Scenario& s) {
  std::vector<double> headings(s.robots.count, 0.0);
  if (s.robots.model != RobotModel::kDiffDrive) return headings;
  const std::optional<double>& fixed = s.robots.diff_drive.start_heading;
  Rng rng(s.seed, "robots.heading");
  for (double& h : headings)
    h = fixed ? *fixed * kPi / 180.0 : rng.Uniform(-kPi, kPi);
  return headings;
}

std::vector<int> RobotStarts(const Scenario& s, const Map& map) {
  const Lattice& lat = map.lattice();
  const int n = s.robots.count;
  std::vector<int> starts;
  if (!s.robots.start.empty()) {
    for (int i = 0; i < n; ++i) {
      const std::string key = "robots.start[" + std::to_string(i) + "]";
      const Vec2& p = s.robots.start[i];
      for (const Box& b : map.obstacles()) {
        if (PointBoxDistanceSq(p, b) < s.robots.radius * s.robots.radius)
          Fail(s, key,
               "start " + Fmt(p) +
                   " is inside an obstacle (the robot disc touches the box " +
                   Fmt(b.lo) + "-" + Fmt(b.hi) + ")");
      }
      const int idx = lat.NearestPoint(p);
      if (!lat.Free(idx))
        Fail(s, key,
             "start " + Fmt(p) + " snaps to lattice point " +
                 Fmt(lat.Point(idx)) +
                 ", which is not free (obstacle or wall within the robot "
                 "radius)");
      for (int j = 0; j < i; ++j) {
        if (starts[j] == idx)
          Fail(s, key,
               "start " + Fmt(p) + " snaps to the same lattice point " +
                   Fmt(lat.Point(idx)) + " as robot " + std::to_string(j));
      }
      starts.push_back(idx);
    }
    return starts;
  }
  std::vector<int> pool;
  for (int idx = 0; idx < lat.size(); ++idx)
    if (lat.Free(idx) && lat.components()[idx] == 0) pool.push_back(idx);
  if (lat.NumFree() == 0)
    Fail(s, "robots.count", "the workspace has no free lattice point");
  if (n > static_cast<int>(pool.size()))
    Fail(s, "robots.count",
         std::to_string(n) + " robots but only " + std::to_string(pool.size()) +
             " free lattice points in the largest connected region (" +
             std::to_string(lat.NumFree()) + " free in all)");
  Rng rng(s.seed, "starts");
  for (int i = 0; i < n; ++i) {  // partial Fisher-Yates
    const size_t j = i + rng.UniformInt(pool.size() - i);
    std::swap(pool[i], pool[j]);
    starts.push_back(pool[i]);
  }
  return starts;
}

// Targets are placed, and prior means drawn, where some lattice point that a
// robot can reach sees them (in range and in sight).
class TargetPlacer {
 public:
  TargetPlacer(const Scenario& s, const Map& map,
               const std::vector<int>& starts)
      : s_(s),
        map_(map),
        lat_(map.lattice()),
        reachable_(lat_.size(), 0),
        reach_(0.9 * s.sensor.range),
        prior_rng_(s.seed, "priors") {
    for (int idx = 0; idx < lat_.size(); ++idx) {
      if (!lat_.Free(idx)) continue;
      for (int r : starts)
        if (lat_.components()[idx] == lat_.components()[r]) reachable_[idx] = 1;
    }
  }

  // Whether some reachable lattice point sees `p` within `reach` (by
  // default 0.9 sensor.range: random targets and prior means keep a margin).
  bool Observable(const Vec2& p) const { return Observable(p, reach_); }
  bool Observable(const Vec2& p, double reach) const {
    const int cx = lat_.Ix(lat_.NearestPoint(p)),
              cy = lat_.Iy(lat_.NearestPoint(p));
    const int k = static_cast<int>(std::ceil(reach / lat_.step())) + 1;
    for (int iy = std::max(0, cy - k); iy <= std::min(lat_.ny() - 1, cy + k);
         ++iy)
      for (int ix = std::max(0, cx - k); ix <= std::min(lat_.nx() - 1, cx + k);
           ++ix) {
        const int idx = lat_.Index(ix, iy);
        if (!reachable_[idx] || (lat_.Point(idx) - p).norm() > reach) continue;
        if (!s_.sensor.line_of_sight || map_.LineOfSight(lat_.Point(idx), p))
          return true;
      }
    return false;
  }

  // The target at `pos` (cfg: its list entry, or null) with its prior.
  void Add(const Vec2& pos, const TargetConfig* cfg, World* w) {
    TargetPrior prior;
    prior.model = cfg ? cfg->dynamics : TargetModel{};
    const int d = prior.model.dim();
    Eigen::VectorXd x0 = Eigen::VectorXd::Zero(d);
    x0.head<2>() = pos;
    if (d == 4 && cfg) x0.tail<2>() = cfg->velocity;
    const double sigma =
        (cfg && cfg->prior_sigma) ? *cfg->prior_sigma : s_.targets.prior_sigma;
    prior.cov = sigma * sigma * Eigen::MatrixXd::Identity(d, d);
    // Default prior mean: the truth plus an offset drawn from
    // N(0, prior_offset^2 I), redrawn (a few times) until the mean lies in
    // free space where a reachable point sees it: the robots know the map,
    // so their prior puts its mean where the target could be observed. Drawn
    // even when a mean is given, so the other targets' draws do not depend
    // on it.
    const double offset = s_.targets.prior_offset;
    prior.mean = x0;
    for (int attempt = 0; attempt < 20; ++attempt) {
      Eigen::VectorXd draw(d);
      for (int c = 0; c < d; ++c) draw[c] = offset * prior_rng_.Normal();
      prior.mean = x0 + draw;
      if (map_.PointFree(prior.mean.head<2>()) &&
          Observable(prior.mean.head<2>()))
        break;
      prior.mean = x0;
    }
    if (cfg && cfg->prior_mean) prior.mean.head<2>() = *cfg->prior_mean;
    w->priors.push_back(std::move(prior));
    w->truth.targets.push_back(std::move(x0));
  }

  // The listed targets (each checked), or `targets.count` random static ones
  // in free space, each observable.
  void PlaceAll(World* w) {
    if (!s_.targets.list.empty()) {
      for (size_t k = 0; k < s_.targets.list.size(); ++k) {
        const std::string key =
            "targets.list[" + std::to_string(k) + "].position";
        const Vec2& p = s_.targets.list[k].position;
        if (!map_.PointFree(p)) {
          const Vec2& size = map_.size();
          if (p.x() < 0 || p.y() < 0 || p.x() > size.x() || p.y() > size.y())
            Fail(s_, key,
                 "target " + Fmt(p) + " is outside the workspace " + Fmt(size));
          Fail(s_, key, "target " + Fmt(p) + " is inside an obstacle");
        }
        // A static target that no point the robots can reach measures (in
        // range, in sight) could never be localized: the mission would
        // run its whole horizon, and the expert plan towards a prior mean
        // elsewhere (issue 37). A moving one may come into view.
        if (s_.targets.list[k].dynamics.IsStatic() &&
            !Observable(p, s_.sensor.range))
          Fail(s_, key,
               "target " + Fmt(p) +
                   " can never be measured: no lattice point the robots can "
                   "reach is within sensor.range (" +
                   FormatNumber(s_.sensor.range) + " m) of it" +
                   (s_.sensor.line_of_sight ? " with a free line of sight"
                                            : "") +
                   " (walled in, or cut off from the robots' starts)");
        Add(p, &s_.targets.list[k], w);
      }
      return;
    }
    const double clearance = 0.05;
    Rng rng(s_.seed, "targets");
    for (int k = 0; k < s_.targets.count; ++k) {
      bool placed = false;
      for (int attempt = 0; attempt < 10000 && !placed; ++attempt) {
        const Vec2 p(rng.Uniform(clearance, map_.size().x() - clearance),
                     rng.Uniform(clearance, map_.size().y() - clearance));
        bool clear = true;
        for (const Box& b : map_.obstacles())
          if (PointBoxDistanceSq(p, b) < clearance * clearance) clear = false;
        if (!clear || !Observable(p)) continue;
        Add(p, nullptr, w);
        placed = true;
      }
      if (!placed)
        Fail(s_, "targets.count",
             "cannot place target " + std::to_string(k) +
                 " where the robots could observe it (the free space is too "
                 "small or cut off)");
    }
  }

 private:
  const Scenario& s_;
  const Map& map_;
  const Lattice& lat_;
  std::vector<char> reachable_;
  double reach_;
  Rng prior_rng_;
};

}  // namespace

World World::Build(const Scenario& s) {
  World w;
  std::optional<GeneratedObstacles> generated;
  w.map = Map(s.workspace.size, AllObstacles(s, &generated), s.workspace.cell,
              s.robots.step, s.robots.radius);
  if (generated) CheckGeneratedLattice(s, *generated, w.map.lattice());
  w.robot_starts = RobotStarts(s, w.map);
  w.robot_headings = StartHeadings(s);
  TargetPlacer(s, w.map, w.robot_starts).PlaceAll(&w);

  // MuJoCo's broad phase needs stack memory quadratic in the number of
  // geoms (the MJCF sizes it so): keep models to a size that fits.
  const int n = s.robots.count;
  // A diff_drive robot is three bodies (chassis and two wheels).
  const bool wheeled = s.robots.model == RobotModel::kDiffDrive;
  const int bodies = (wheeled ? 3 : 1) * n + w.NumTargets() +
                     static_cast<int>(w.map.obstacles().size());
  if (bodies > kMaxBodies)
    Fail(s, s.targets.list.empty() ? "targets.count" : "targets.list",
         std::to_string(n) +
             (wheeled ? " diff_drive robots (3 bodies each), " : " robots, ") +
             std::to_string(w.NumTargets()) + " targets and " +
             std::to_string(w.map.obstacles().size()) +
             " obstacle boxes make " + std::to_string(bodies) +
             " bodies; aia simulates at most " + std::to_string(kMaxBodies));
  // MuJoCo 2.2 keeps its constraint arrays dense (njmax^2 and njmax nv
  // numbers): a wheeled team's resting contacts make them grow as N^2.
  const MujocoModelSizes mujoco = ModelSizesOf(w, s);
  const double bytes = MujocoDataBytes(mujoco.sizes, mujoco.nv, 0);
  if (bytes > kMaxPhysicsBytes) {
    char what[400];
    std::snprintf(
        what, sizeof(what),
        "%d %s robots need %.1f GiB of MuJoCo 2.2's constraint "
        "arrays (dense in the contacts: %d resting and possible), "
        "more than the %.1f GiB MuJoCo 2.2 can hold in one mjData; fewer "
        "robots%s",
        n, EnumNameOf(s.robots.model), bytes / (1L << 30), mujoco.sizes.nconmax,
        kMaxPhysicsBytes / (1L << 30),
        wheeled ? ", or robots.model: point" : "");
    Fail(s, "robots.count", what);
  }

  // Failures: "random" picks a robot from the seed's own stream, one that
  // no entry names and no random entry drew before (redrawn: the first
  // draw is kept where it is free, so a lone random entry fails the robot
  // it always did); Scenario::Validate leaves one free for each.
  Rng fail_rng(s.seed, "failures");
  std::vector<std::uint8_t> taken(n, 0);
  for (const RobotFailure& f : s.communication.failures)
    if (f.robot != RobotFailure::kRandomRobot) taken[f.robot] = 1;
  for (const RobotFailure& f : s.communication.failures) {
    RobotFailure resolved = f;
    if (f.robot == RobotFailure::kRandomRobot) {
      do {
        resolved.robot = static_cast<int>(fail_rng.UniformInt(n));
      } while (taken[resolved.robot]);
      taken[resolved.robot] = 1;
    }
    w.truth.failures.push_back(resolved);
  }
  return w;
}

}  // namespace aia
