#include "aia/scenario/config.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <system_error>

#include "aia/core/hash.h"

namespace aia {
namespace {

std::string RobotIndexText(int count) {
  return "[0, " + std::to_string(count - 1) + "] (robots.count is " +
         std::to_string(count) + ")";
}

bool Inside(const Vec2& p, const Vec2& size) {
  return p.x() >= 0.0 && p.y() >= 0.0 && p.x() <= size.x() && p.y() <= size.y();
}

// The generator's parameters against the robots and the workspace: every
// width is at least one lattice step, walls fit between lattice points, and
// the layout fits in the workspace.
void CheckGenerator(const Scenario& s, const FieldChecker& check) {
  const GeneratorConfig& g = *s.workspace.obstacles.generator;
  const double step = s.robots.step, radius = s.robots.radius;
  const std::string type = GeneratorTypeName(g.type);
  const std::string step_text =
      "one lattice step (robots.step " + FormatNumber(step) + ")";
  // With a margin of 1e-9 m: a wall at the limit itself (0.29 beside
  // 0.5 - 2 x 0.105) can pass the subtraction's rounding and then touch the
  // lattice's discs.
  if (g.HasWalls() && !(g.wall < step - 2 * radius - 1e-9)) {
    check.Fail(g.wall, "must be less than robots.step - 2 robots.radius (" +
                           FormatNumber(step - 2 * radius) +
                           "): walls stand on the lines between lattice "
                           "points, and a thicker one would touch a robot on "
                           "the points beside it; got " +
                           FormatNumber(g.wall));
  }
  // A wheeled robot arrives anywhere within physics.tolerance of its point
  // and drives on from there: with less room beside a wall than that it
  // catches the wall's end (walls of 0.19 beside 0.5 - 2 x 0.15, 5 mm a
  // side, jammed robots for the rest of the mission).
  const double tolerance = s.physics.tolerance;
  if (g.HasWalls() && s.robots.model == RobotModel::kDiffDrive &&
      !(g.wall < step - 2 * (radius + tolerance) - 1e-9)) {
    check.Fail(g.wall,
               "must be less than robots.step - 2 (robots.radius + "
               "physics.tolerance) (" +
                   FormatNumber(step - 2 * (radius + tolerance)) +
                   ") for diff_drive robots: a wheeled robot is anywhere "
                   "within the tolerance of its lattice point, and a thicker "
                   "wall would catch it passing; got " +
                   FormatNumber(g.wall));
  }
  if (g.HasCorridors() && StepsIn(g.corridor, step) < 1) {
    check.Fail(g.corridor, "is narrower than " + step_text + ": the robots " +
                               "move between lattice points, so a corridor " +
                               "is at least one step wide; got " +
                               FormatNumber(g.corridor));
  }
  if (g.HasRooms()) {
    if (g.door < 2 * radius) {
      check.Fail(g.door, "is narrower than a robot (robots.radius " +
                             FormatNumber(radius) + ", " +
                             FormatNumber(2 * radius) +
                             " m across); a door is at least " + step_text +
                             " wide; got " + FormatNumber(g.door));
    }
    if (StepsIn(g.door, step) < 1) {
      check.Fail(g.door, "is narrower than " + step_text +
                             ": the robots move between lattice points, so a "
                             "door is at least one step wide; got " +
                             FormatNumber(g.door));
    }
    if (g.room_size.x() < g.door) {
      check.Fail(g.room_size, "min must be at least door (" +
                                  FormatNumber(g.door) +
                                  ") so that every room has a whole door, "
                                  "got " +
                                  FormatPair(g.room_size.x(), g.room_size.y()));
    }
  }
  const int nx = StepsIn(s.workspace.size.x(), step),
            ny = StepsIn(s.workspace.size.y(), step);
  const std::string workspace =
      "the workspace " + FormatPair(s.workspace.size.x(), s.workspace.size.y());
  if (g.type == GeneratorType::kMaze) {
    // Maze cells of `corridor`: with one cell across, the spanning tree
    // opens every wall, and the world comes out empty.
    const int p = StepsIn(g.corridor, step);
    if (p >= 1 && (nx / p < 2 || ny / p < 2)) {
      check.Fail(g.corridor, workspace +
                                 " holds fewer than two maze cells of it in "
                                 "one direction (" +
                                 FormatNumber(2 * p * step) +
                                 " m needed in both), so the maze would have "
                                 "no wall; got " +
                                 FormatNumber(g.corridor));
    }
  }
  if (g.type == GeneratorType::kRooms) {
    // Every room is at least min across (a region is split only where both
    // halves keep it), the workspace itself being the first room: one
    // narrower than min holds no room of the size asked for (it came out
    // as one room and no wall).
    const GeneratorConfig::RoomSteps rooms = g.RoomStepsAt(step);
    const int m = rooms.min;
    if (std::min(nx, ny) < m) {
      check.Fail(g.room_size,
                 workspace + " is narrower than the rooms' min side (" +
                     FormatNumber(m * step) + " m), so it holds no room; got " +
                     FormatPair(g.room_size.x(), g.room_size.y()));
    }
    // The generator's first split (world/generator.cc, Rooms): with neither
    // side split, the workspace is one room and no wall.
    if (!rooms.Splits(nx) && !rooms.Splits(ny)) {
      check.Fail(g.room_size,
                 workspace +
                     " would be one room and no wall: a side is split only "
                     "where it is longer than the rooms' max side (" +
                     FormatNumber(rooms.max * step) +
                     " m) and holds two of their "
                     "min side (" +
                     FormatNumber(2 * m * step) + " m); got " +
                     FormatPair(g.room_size.x(), g.room_size.y()));
    }
  }
  if (g.type == GeneratorType::kCorridors) {
    const int need = StepsIn(g.corridor, step) + StepsIn(g.room_size.x(), step);
    if (std::min(nx, ny) < need) {
      check.Fail(g, workspace + " is too small for a corridor of " +
                        FormatNumber(g.corridor) + " m with rooms of " +
                        FormatNumber(g.room_size.x()) + " m beside it (" +
                        FormatNumber(need * step) +
                        " m in both directions); a larger workspace, or a "
                        "narrower corridor or smaller rooms");
    }
  }
}

// The workspace's bounds as messages show them.
std::string BoundsText(const Vec2& size) {
  return "[0, " + FormatNumber(size.x()) + "] x [0, " + FormatNumber(size.y()) +
         "]";
}

// The name labels one-line messages and the MuJoCo model (escaped there):
// a line break or another control character has no place in it.
void CheckName(const Scenario& s, const FieldChecker& check) {
  for (std::size_t i = 0; i < s.name.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(s.name[i]);
    if (c < 0x20 || c == 0x7f) {
      char code[8];
      std::snprintf(code, sizeof code, "0x%02x", c);
      check.Fail(s.name, "holds a control character (" + std::string(code) +
                             " at character " + std::to_string(i + 1) +
                             "); a name is one line of printable text");
    }
  }
}

// At most one video frame per physics step (`aia render`'s frame clock).
void CheckFrameRate(const Scenario& s, const FieldChecker& check) {
  const int max_fps =
      static_cast<int>(std::floor(1.0 / s.physics.timestep + 1e-9));
  if (s.render.fps > max_fps)
    check.Fail(s.render.fps, "must be in [1, " + std::to_string(max_fps) +
                                 "] (at most one frame per physics step of " +
                                 FormatNumber(s.physics.timestep) +
                                 " s), got " + std::to_string(s.render.fps));
}

// Derived sizes, before anything is allocated (the ranges keep these
// products finite and far from integer overflow): grid cells, lattice
// points and simulated bodies.
void CheckDerivedSizes(const Scenario& s, const FieldChecker& check) {
  const Vec2& size = s.workspace.size;
  const double cells = std::ceil(size.x() / s.workspace.cell) *
                       std::ceil(size.y() / s.workspace.cell);
  if (cells > limits::kMaxGridCells) {
    check.Fail(s.workspace.cell,
               "makes " + FormatNumber(cells) +
                   " occupancy-grid cells in the workspace " +
                   FormatPair(size.x(), size.y()) + "; at most " +
                   FormatNumber(limits::kMaxGridCells) + " (a larger cell)");
  }
  const double points = std::floor(size.x() / s.robots.step + 1e-9) *
                        std::floor(size.y() / s.robots.step + 1e-9);
  if (points > limits::kMaxLatticePoints) {
    check.Fail(s.robots.step, "makes " + FormatNumber(points) +
                                  " lattice points in the workspace " +
                                  FormatPair(size.x(), size.y()) +
                                  "; at most " +
                                  FormatNumber(limits::kMaxLatticePoints) +
                                  " (a larger step or a smaller workspace)");
  }
  const int random_boxes =
      s.workspace.obstacles.random ? s.workspace.obstacles.random->count : 0;
  // A diff_drive robot is three bodies (chassis and two wheels).
  const bool wheeled = s.robots.model == RobotModel::kDiffDrive;
  const long robot_bodies = (wheeled ? 3L : 1L) * s.robots.count;
  const long bodies = robot_bodies + s.NumTargets() + random_boxes +
                      static_cast<long>(s.workspace.obstacles.boxes.size());
  if (bodies > limits::kMaxBodies) {
    const std::string what =
        std::to_string(s.robots.count) +
        (wheeled ? " diff_drive robots (3 bodies each), " : " robots, ") +
        std::to_string(s.NumTargets()) + " targets and " +
        std::to_string(bodies - robot_bodies - s.NumTargets()) +
        " obstacle boxes make " + std::to_string(bodies) +
        " bodies; aia simulates at most " + std::to_string(limits::kMaxBodies);
    if (random_boxes >= s.robots.count && random_boxes >= s.NumTargets())
      check.Fail(s.workspace.obstacles.random->count, what);
    if (s.robots.count >= s.NumTargets()) check.Fail(s.robots.count, what);
    if (s.targets.list.empty()) check.Fail(s.targets.count, what);
    check.Fail(s.targets.list, what);
  }
}

// Obstacle boxes and random boxes against the workspace, then the
// generator's parameters.
void CheckObstacles(const Scenario& s, const FieldChecker& check) {
  const Vec2& size = s.workspace.size;
  for (const BoxConfig& b : s.workspace.obstacles.boxes) {
    const Vec2 lo = b.center - 0.5 * b.size, hi = b.center + 0.5 * b.size;
    if (!(lo.x() < size.x() && lo.y() < size.y() && hi.x() > 0.0 &&
          hi.y() > 0.0)) {
      check.Fail(b.center, "box " + check.Shown(b.center) + " of size " +
                               check.Shown(b.size) +
                               " lies outside the workspace " +
                               BoundsText(size));
    }
  }
  // A block that draws no box (count 0, the way to swap random boxes for a
  // generator or a map) holds no world back.
  if (const auto& random = s.workspace.obstacles.random;
      random && random->count > 0 &&
      (random->max_size.array() > size.array()).any()) {
    check.Fail(random->max_size,
               "must not be larger than the workspace " +
                   FormatPair(size.x(), size.y()) + ", got " +
                   FormatPair(random->max_size.x(), random->max_size.y()));
  }
  if (s.workspace.obstacles.generator) CheckGenerator(s, check);
}

void CheckCommunicationRange(const Scenario& s, const FieldChecker& check) {
  if (s.communication.mode != CommMode::kRange &&
      s.communication.range != CommParams{}.range)
    check.Warn(s.communication.range,
               "applies to communication.mode range only; with mode full "
               "every pair of active robots talks, so it changes nothing");
}

// sensor.rate and mission.avoidance apply to asynchronous decisions only;
// a rate is sensed on the physics steps.
void CheckAsyncKeys(const Scenario& s, const FieldChecker& check) {
  const std::optional<double>& rate = s.sensor.rate;
  if (rate && s.mission.decisions != Decisions::kAsync) {
    check.Fail(rate,
               "applies to mission.decisions async only (lockstep senses once "
               "per decision step); remove it, or set mission.decisions: "
               "async");
  }
  if (rate) {
    const long steps = SensingTickSteps(*rate, s.physics.timestep);
    const double hz = 1.0 / (static_cast<double>(steps) * s.physics.timestep);
    if (std::abs(hz - *rate) > 1e-6 * *rate)
      check.Warn(rate,
                 "is sensed at " + FormatNumber(hz) +
                     " Hz: a tick falls on a physics step, every " +
                     std::to_string(steps) + " of physics.timestep " +
                     FormatNumber(s.physics.timestep) +
                     " s (targets take a step of their dynamics per tick)");
  }
  if (s.mission.avoidance && s.mission.decisions != Decisions::kAsync) {
    check.Fail(s.mission.avoidance,
               "applies to mission.decisions async only (in lockstep robots "
               "move together); remove it, or set mission.decisions: async");
  }
}

// Obstacles are checked against positions when the world is built; here
// only the workspace bounds [0, size] are, robots' and then targets'.
void CheckPositions(const Scenario& s, const FieldChecker& check) {
  const Vec2& size = s.workspace.size;
  for (const Vec2& p : s.robots.start) {
    if (!Inside(p, size)) {
      check.Fail(p, "must lie inside the workspace " + BoundsText(size) +
                        ", got " + check.Shown(p));
    }
  }
  for (const TargetConfig& t : s.targets.list) {
    if (!Inside(t.position, size)) {
      check.Fail(t.position, "must lie inside the workspace " +
                                 BoundsText(size) + ", got " +
                                 check.Shown(t.position));
    }
  }
}

// communication.failures: robot indices in range, each robot named once,
// and a robot of its own for each random entry.
void CheckFailures(const Scenario& s, const FieldChecker& check) {
  const int robots = s.robots.count;
  std::set<int> named;
  int random_failures = 0;
  for (const RobotFailure& f : s.communication.failures) {
    if (f.robot >= robots) {
      check.Fail(f.robot, "must be a robot index in " + RobotIndexText(robots) +
                              " or random, got " + check.Shown(f.robot));
    }
    if (f.robot == RobotFailure::kRandomRobot) {
      ++random_failures;
    } else if (!named.insert(f.robot).second) {
      // Which of two steps would fail it? Said once.
      check.Fail(f.robot, "robot " + std::to_string(f.robot) +
                              " is named by two failure entries: give each "
                              "robot one failure step");
    }
  }
  // Each random entry fails a robot of its own (world.cc).
  if (const int free = robots - static_cast<int>(named.size());
      random_failures > free) {
    check.Fail(s.communication.failures,
               std::to_string(random_failures) + " random entries, but " +
                   std::to_string(free) +
                   (free == 1 ? " robot is" : " robots are") +
                   " not named by another entry: each random entry fails a "
                   "robot of its own");
  }
}

void CheckFollowRobot(const Scenario& s, const FieldChecker& check) {
  if (s.render.follow_robot >= s.robots.count) {
    check.Fail(s.render.follow_robot,
               "must be -1 (no robot) or a robot index in " +
                   RobotIndexText(s.robots.count) + ", got " +
                   check.Shown(s.render.follow_robot));
  }
}

}  // namespace

void RandomObstaclesConfig::Validate(const FieldChecker& check) {
  if ((min_size.array() > max_size.array()).any()) {
    check.Fail(min_size, "must not exceed max_size " +
                             FormatPair(max_size.x(), max_size.y()) +
                             " in either component, got " +
                             FormatPair(min_size.x(), min_size.y()));
  }
}

const char* GeneratorTypeName(GeneratorType type) {
  for (const auto& n : EnumNames(GeneratorType{}))
    if (n.value == type) return n.name;
  return "?";
}

void GeneratorConfig::Validate(const FieldChecker& check) {
  // A key of another kind of world, given a value of its own: said, not
  // refused (effective.yaml writes every key, and a --set of the type
  // leaves the file's keys behind).
  const GeneratorConfig unset;
  const std::string kind = GeneratorTypeName(type);
  const auto unused = [&](const auto& field, const auto& default_value,
                          bool used, const char* users) {
    if (!used && !(field == default_value))
      check.Warn(field, std::string("applies to ") + users + " only; a " +
                            kind + " changes nothing by it");
  };
  unused(wall, unset.wall, HasWalls(), "maze, rooms and corridors");
  unused(corridor, unset.corridor, HasCorridors(), "maze and corridors");
  unused(door, unset.door, HasRooms(), "rooms and corridors");
  unused(room_size, unset.room_size, HasRooms(), "rooms and corridors");
  unused(loops, unset.loops, type == GeneratorType::kMaze, "a maze");
  const bool cave = type == GeneratorType::kCave;
  unused(fill, unset.fill, cave, "a cave");
  unused(smoothing, unset.smoothing, cave, "a cave");
  unused(cell, unset.cell, cave, "a cave");
  if (!HasRooms()) return;
  const std::string shown = FormatPair(room_size.x(), room_size.y());
  if (room_size.x() > room_size.y())
    check.Fail(room_size,
               "min must not exceed max ([min, max] metres), got " + shown);
  if (room_size.y() < 2 * room_size.x())
    check.Fail(room_size,
               "max must be at least twice min, so that a part larger than "
               "max can be split into two rooms of at least min, got " +
                   shown);
}

void ObstaclesConfig::Validate(const FieldChecker& check) {
  if (generator) {
    const std::string why =
        ": a generated world fills the whole workspace and keeps its free "
        "space connected, which other obstacles could break; use one or the "
        "other";
    if (random && random->count > 0)
      check.Fail(*generator,
                 "cannot be combined with workspace.obstacles.random (" +
                     std::to_string(random->count) +
                     " boxes; a count of 0 would do)" + why);
    if (!boxes.empty())
      check.Fail(*generator,
                 "cannot be combined with workspace.obstacles.boxes" + why);
    if (!map.empty())
      check.Fail(*generator,
                 "cannot be combined with workspace.obstacles.map" + why);
  }
  if (map.empty() && map_threshold != ObstaclesConfig{}.map_threshold)
    check.Warn(map_threshold,
               "applies to workspace.obstacles.map only, and no map is given: "
               "it changes nothing");
  if (map.empty()) return;
  // Only existence here: the image is decoded by world/, which owns the
  // occupancy grid.
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(map, ec)) {
    check.Fail(map, "map file does not exist: " + map +
                        " (a relative path in a scenario file is resolved "
                        "against the file's folder, one given by --set "
                        "against the working folder)");
  }
  if (!fs::is_regular_file(map, ec))
    check.Fail(map, "map is not a file: " + map);
}

void PolicyConfig::Validate(const FieldChecker& check) {
  if (model_sha256 && !IsSha256Hex(*model_sha256))
    check.Fail(model_sha256,
               "must be 64 lower-case hexadecimal digits (a SHA-256 as "
               "sha256sum prints it), got '" +
                   *model_sha256 + "'");
}

void WorkspaceConfig::Validate(const FieldChecker& check) {
  if (cell > size.minCoeff()) {
    check.Fail(cell, "must not be larger than the smaller workspace side (" +
                         FormatNumber(size.minCoeff()) + "), got " +
                         FormatNumber(cell));
  }
}

void DiffDriveConfig::Validate(const FieldChecker& check) {
  // The chassis stands on its wheels: it must reach above their axle.
  if (!(height > wheel_radius)) {
    check.Fail(height, "must be more than wheel_radius (" +
                           FormatNumber(wheel_radius) +
                           "): the chassis sits on the wheels' axle, got " +
                           FormatNumber(height));
  }
}

void RobotsConfig::Validate(const FieldChecker& check) {
  if (model == RobotModel::kDiffDrive) {
    // Wheels and casters inside the disc: only the chassis meets obstacles.
    const double wheels = 0.5 * diff_drive.track + kDiffDriveWheelHalfWidth;
    if (!(wheels < radius)) {
      check.Fail(diff_drive.track,
                 "puts the wheels outside the robot's disc: track / 2 + "
                 "the wheel's half width (" +
                     FormatNumber(kDiffDriveWheelHalfWidth) + ") is " +
                     FormatNumber(wheels) + ", robots.radius " +
                     FormatNumber(radius) +
                     " (a narrower track or a larger radius)");
    }
    if (!(diff_drive.wheel_radius < 0.5 * radius)) {
      check.Fail(diff_drive.wheel_radius,
                 "must be less than half of robots.radius (" +
                     FormatNumber(0.5 * radius) +
                     ") so that the casters fit in front of and behind the "
                     "axle, got " +
                     FormatNumber(diff_drive.wheel_radius));
    }
  }
  if (model == RobotModel::kPoint) {
    const std::vector<std::string> set =
        ChangedFields(diff_drive, DiffDriveConfig{});
    if (!set.empty())
      check.Warn(diff_drive,
                 "sets " + field_text::Join(set, ", ") +
                     ", which only robots.model diff_drive reads: point robots "
                     "change nothing by " +
                     (set.size() == 1 ? "it" : "them"));
  }
  if (!(radius < step / 2)) {
    check.Fail(radius, "must be less than half of robots.step (" +
                           FormatNumber(step / 2) +
                           ") so that robots on neighbouring lattice points "
                           "do not touch, got " +
                           FormatNumber(radius));
  }
  // An empty list is no list: random starts.
  if (!start.empty() && static_cast<int>(start.size()) != count) {
    check.Fail(start, "has " + std::to_string(start.size()) +
                          " positions but robots.count is " +
                          std::to_string(count) +
                          "; give one [x, y] per robot, or omit start for "
                          "random ones");
  }
}

void TargetConfig::Validate(const FieldChecker& check) {
  // With a 2-D state the velocity would be silently ignored.
  if (dynamics.dim() != 4 && !velocity.isZero(0.0)) {
    check.Fail(velocity,
               "needs 4x4 dynamics.A (state [px, py, vx, vy]); this target's "
               "state is its position only");
  }
}

void TargetsConfig::Validate(const FieldChecker& check) {
  const bool has_count = check.Given(count), has_list = !list.empty();
  if (has_count && has_list && count != static_cast<int>(list.size())) {
    check.Fail(count, "is " + std::to_string(count) + " but targets.list has " +
                          std::to_string(list.size()) +
                          " targets; give count (random targets) or list, or "
                          "make them agree");
  }
  if (Num() == 0) {
    const std::string what =
        "at least one target is required: give targets.count (random static "
        "targets) or targets.list";
    if (has_count) check.Fail(count, what);
    if (check.Given(list)) check.Fail(list, what);
    check.Fail(*this, what);
  }
  // Defaults that no target takes: every target of the list gives its own
  // (prior_mean is the position's: a 4-D target's velocity mean is drawn).
  if (has_list) {
    bool all_means = true, all_sigmas = true;
    for (const TargetConfig& t : list) {
      all_means &= t.prior_mean.has_value() && t.dynamics.dim() == 2;
      all_sigmas &= t.prior_sigma.has_value();
    }
    const TargetsConfig unset;
    if (all_means && prior_offset != unset.prior_offset)
      check.Warn(prior_offset,
                 "every target of targets.list gives its prior_mean, so no "
                 "prior mean is drawn: it changes nothing");
    if (all_sigmas && prior_sigma != unset.prior_sigma)
      check.Warn(prior_sigma,
                 "every target of targets.list gives its prior_sigma: it "
                 "changes nothing");
  }
  // With a list, count is its length (so that the effective scenario
  // states both consistently).
  if (has_list) count = static_cast<int>(list.size());
}

double PhysicsConfig::PointArrivalSeconds(double step) const {
  // The waypoint spring is critically damped: from rest `step` away, the
  // distance left after t is step (1 + w t) e^(-w t), w = sqrt(kp / mass),
  // which falls monotonically; bisection on x = w t for the tolerance.
  const double omega = std::sqrt(kp / robot_mass);
  const double ratio = tolerance / step;
  if (ratio >= 1.0) return 0.0;
  double lo = 0.0, hi = 1.0;
  while ((1.0 + hi) * std::exp(-hi) > ratio) hi *= 2.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    ((1.0 + mid) * std::exp(-mid) > ratio ? lo : hi) = mid;
  }
  return hi / omega;
}

void PhysicsConfig::Validate(const FieldChecker& check, RobotModel model,
                             double step) {
  // A robot has arrived within tolerance of its waypoint: beyond half a
  // lattice step it would arrive nearer the point it left than the one it
  // goes to.
  if (tolerance >= 0.5 * step) {
    check.Fail(tolerance, "must be below half of robots.step (" +
                              FormatNumber(0.5 * step) + "), got " +
                              FormatNumber(tolerance));
    return;
  }
  // The point robots' spring, given to wheeled ones: said, not refused.
  if (model == RobotModel::kDiffDrive) {
    const PhysicsConfig unset;
    if (kp != unset.kp)
      check.Warn(kp,
                 "applies to point robots only (a diff_drive robot is driven "
                 "by its motors, robots.diff_drive): it changes nothing");
    if (robot_mass != unset.robot_mass)
      check.Warn(robot_mass,
                 "applies to point robots only (a diff_drive robot weighs "
                 "robots.diff_drive.mass): it changes nothing");
  }
  // A point robot's waypoint actuator is a critically damped spring:
  // explicit integration is stable while timestep * omega stays well below
  // 1. (A wheeled robot's motors are damped implicitly.)
  const double omega_dt = timestep * std::sqrt(kp / robot_mass);
  if (model == RobotModel::kPoint && omega_dt > 0.5) {
    check.Fail(kp, "is too stiff for physics.timestep " +
                       FormatNumber(timestep) + " and robot_mass " +
                       FormatNumber(robot_mass) +
                       ": timestep * sqrt(kp / robot_mass) is " +
                       FormatNumber(omega_dt) +
                       ", at most 0.5 keeps the simulation stable (lower kp "
                       "or the timestep)");
  }
  // The stall rule judges a point robot that moves slower than kStallSpeed
  // from kSettleTime on blocked. Near its waypoint the spring's speed is
  // below omega x at distance x, so within kStallSpeed / omega of it the
  // robot is slow: a tolerance inside that stalls every move short of its
  // point. And from rest the robot must be faster than that at kSettleTime,
  // step omega^2 t e^(-omega t), unless it has arrived by then.
  if (model == RobotModel::kPoint) {
    // Two significant digits, rounded up: what the message says is enough.
    const auto up = [](double x) {
      const double unit = std::pow(10.0, std::floor(std::log10(x)) - 1.0);
      return std::ceil(x / unit) * unit;
    };
    const double omega = std::sqrt(kp / robot_mass);
    const double slow_within = kStallSpeed / omega;
    if (tolerance < 1.5 * slow_within) {
      check.Fail(tolerance,
                 "must be at least " + FormatNumber(up(1.5 * slow_within)) +
                     " for kp " + FormatNumber(kp) + " and robot_mass " +
                     FormatNumber(robot_mass) +
                     ": a point robot slows below the stall rule's " +
                     FormatNumber(kStallSpeed) + " m/s within " +
                     FormatNumber(up(slow_within)) +
                     " m of its waypoint, and would end every move as "
                     "stalled short of it (raise the tolerance or kp), got " +
                     FormatNumber(tolerance));
      return;
    }
    const double t = kSettleTime;
    const double speed = step * omega * omega * t * std::exp(-omega * t);
    if (PointArrivalSeconds(step) > t && speed < kStallSpeed) {
      check.Fail(kp, "is too soft for robot_mass " + FormatNumber(robot_mass) +
                         ": a point robot starting a move is still slower "
                         "than the stall rule's " +
                         FormatNumber(kStallSpeed) + " m/s after " +
                         FormatNumber(t) + " s (" + FormatNumber(up(speed)) +
                         " m/s) and would end every move as stalled where "
                         "it started (raise kp)");
      return;
    }
  }
  const double timeout = StepTimeout(model);
  // A point robot's move takes the spring's time to come within tolerance
  // of a waypoint one lattice step away: a decision step shorter than that
  // times every robot out, and none ever moves.
  // (The timesteps' explicit integration arrives a few per cent sooner
  // than the continuous spring: a quarter of slack.)
  const double move = std::round(PointArrivalSeconds(step) * 1e3) / 1e3;
  if (model == RobotModel::kPoint && 0.75 * move > timeout) {
    const std::string why =
        "a point robot's move takes about " + FormatNumber(move) +
        " s (the waypoint spring, kp " + FormatNumber(kp) + " and robot_mass " +
        FormatNumber(robot_mass) + ", from robots.step " + FormatNumber(step) +
        " to within tolerance " + FormatNumber(tolerance) + ")";
    if (step_timeout) {
      check.Fail(step_timeout, "must be at least " + FormatNumber(0.75 * move) +
                                   ": " + why + ", got " +
                                   FormatNumber(timeout));
    } else {
      check.Fail(kp, "is too soft: " + why +
                         ", longer than the step_timeout "
                         "of " +
                         FormatNumber(timeout) +
                         " s (raise kp or physics.step_timeout)");
    }
  }
  const double steps = timeout / timestep;
  if (steps > limits::kMaxPhysicsStepsPerDecision) {
    check.Fail(timestep, "makes " + FormatNumber(steps) +
                             " physics steps in one decision step "
                             "(step_timeout " +
                             FormatNumber(timeout) + " / timestep); at most " +
                             FormatNumber(limits::kMaxPhysicsStepsPerDecision));
  }
}

void RenderConfig::Validate(const FieldChecker& check) {
  for (const int* side : {&width, &height}) {
    if (*side % 2 != 0)
      check.Fail(*side,
                 "must be an even number of pixels in [16, 8192] (H.264 "
                 "needs even sides), got " +
                     std::to_string(*side));
  }
}

// The sections' relations, topic by topic; the first that fails is the
// error, so the order of the checks is the order of their messages.
void Scenario::Validate(const FieldChecker& check) {
  CheckName(*this, check);
  CheckFrameRate(*this, check);
  CheckDerivedSizes(*this, check);
  CheckObstacles(*this, check);
  physics.Validate(check, robots.model, robots.step);
  CheckCommunicationRange(*this, check);
  CheckAsyncKeys(*this, check);
  CheckPositions(*this, check);
  CheckFailures(*this, check);
  CheckFollowRobot(*this, check);
}

InputError Scenario::ErrorAt(const std::string& key,
                             const std::string& what) const {
  return KeyError(ErrorFile(), sources, key, what);
}

int Scenario::LineOf(const std::string& key) const {
  return ErrorAt(key, "").line();
}

}  // namespace aia
