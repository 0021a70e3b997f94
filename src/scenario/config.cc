#include "aia/scenario/config.h"

#include <filesystem>
#include <string>
#include <system_error>

namespace aia {
namespace {

std::string RobotIndexText(int count) {
  return "[0, " + std::to_string(count - 1) + "] (robots.count is " +
         std::to_string(count) + ")";
}

bool Inside(const Vec2& p, const Vec2& size) {
  return p.x() >= 0.0 && p.y() >= 0.0 && p.x() <= size.x() && p.y() <= size.y();
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

void ObstaclesConfig::Validate(const FieldChecker& check) {
  if (map.empty()) return;
  // Only existence here: the image is decoded by world/, which owns the
  // occupancy grid.
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(map, ec)) {
    check.Fail(map, "map file does not exist: " + map +
                        " (relative paths are resolved against the "
                        "scenario's directory)");
  }
  if (!fs::is_regular_file(map, ec))
    check.Fail(map, "map is not a file: " + map);
}

void WorkspaceConfig::Validate(const FieldChecker& check) {
  if (cell > size.minCoeff()) {
    check.Fail(cell, "must not be larger than the smaller workspace side (" +
                         FormatNumber(size.minCoeff()) + "), got " +
                         FormatNumber(cell));
  }
}

void RobotsConfig::Validate(const FieldChecker& check) {
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
  // With a list, count is its length (so that the effective scenario
  // states both consistently).
  if (has_list) count = static_cast<int>(list.size());
}

void Scenario::Validate(const FieldChecker& check) {
  const Vec2& size = workspace.size;
  const std::string bounds = "[0, " + FormatNumber(size.x()) + "] x [0, " +
                             FormatNumber(size.y()) + "]";
  if (const auto& random = workspace.obstacles.random;
      random && (random->max_size.array() > size.array()).any()) {
    check.Fail(random->max_size,
               "must not be larger than the workspace " +
                   FormatPair(size.x(), size.y()) + ", got " +
                   FormatPair(random->max_size.x(), random->max_size.y()));
  }
  // Obstacles are checked against positions when the world is built; here
  // only the workspace bounds [0, size] are.
  for (const Vec2& p : robots.start) {
    if (!Inside(p, size)) {
      check.Fail(p, "must lie inside the workspace " + bounds + ", got " +
                        check.Shown(p));
    }
  }
  for (const TargetConfig& t : targets.list) {
    if (!Inside(t.position, size)) {
      check.Fail(t.position, "must lie inside the workspace " + bounds +
                                 ", got " + check.Shown(t.position));
    }
  }
  for (const RobotFailure& f : communication.failures) {
    if (f.robot >= robots.count) {
      check.Fail(f.robot, "must be a robot index in " +
                              RobotIndexText(robots.count) +
                              " or random, got " + check.Shown(f.robot));
    }
  }
  if (render.follow_robot >= robots.count) {
    check.Fail(render.follow_robot,
               "must be -1 (no robot) or a robot index in " +
                   RobotIndexText(robots.count) + ", got " +
                   check.Shown(render.follow_robot));
  }
}

InputError Scenario::ErrorAt(const std::string& key,
                             const std::string& what) const {
  return KeyError(ErrorFile(), sources, key, what);
}

int Scenario::LineOf(const std::string& key) const {
  return ErrorAt(key, "").line();
}

}  // namespace aia
