// Typed configuration of one mission, one section per struct. Every field is
// declared once, in its struct's Serialize(): its key (the member's name), its
// default (the member's initializer), its allowed values and its meaning.
// The loader, the effective.yaml writer and the key table of
// docs/scenarios.md (`aia schema`) are generic walks over these declarations.
// Sections used at run time by lower modules are their own structs: the
// sensor (estimation's SensorModel), target dynamics (TargetModel) and
// communication (comm's CommParams).
#ifndef AIA_SCENARIO_CONFIG_H_
#define AIA_SCENARIO_CONFIG_H_

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "aia/comm/graph.h"
#include "aia/core/config_node.h"
#include "aia/core/error.h"
#include "aia/core/field_io.h"
#include "aia/core/fields.h"
#include "aia/core/types.h"
#include "aia/estimation/sensor_model.h"
#include "aia/estimation/target_model.h"

namespace aia {

// Hard limits of a scenario (docs/scenarios.md, "Limits"). The declared
// ranges and Scenario::Validate keep every length, count and derived size
// inside them, so that integer arithmetic stays in range and every
// allocation is bounded before anything is built.
namespace limits {
inline constexpr double kMinLength = 1e-3;  // smallest length, metres
inline constexpr double kMaxLength = 1e4;   // largest length, metres
// Occupancy-grid cells (workspace area / cell^2), one byte each.
inline constexpr double kMaxGridCells = 5e7;
// Motion-lattice points (workspace area / step^2).
inline constexpr double kMaxLatticePoints = 1e6;
// Robots, targets and obstacle boxes together (MuJoCo's memory for its broad
// phase grows with the square of this).
inline constexpr int kMaxBodies = 5000;
// Decision steps of a mission.
inline constexpr double kMaxSteps = 1e6;
// Physics steps in one decision step (step_timeout / timestep).
inline constexpr double kMaxPhysicsStepsPerDecision = 1e6;
}  // namespace limits

// The range of lengths: [kMinLength, kMaxLength] metres.
inline constexpr NumberRange kLength{limits::kMinLength, limits::kMaxLength};
// Coordinates: [-kMaxLength, kMaxLength] metres.
inline constexpr NumberRange kCoordinate{-limits::kMaxLength,
                                         limits::kMaxLength};
// Prior standard deviations: [1e-6, 1e6] (det Sigma stays a normal double
// in every dimension aia uses).
inline constexpr NumberRange kPriorSigma{1e-6, 1e6};

struct RandomObstaclesConfig {
  int count = 30;
  Vec2 min_size{0.4, 0.4};
  Vec2 max_size{2.0, 2.0};

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(count)
                 .In(Between(0, limits::kMaxBodies))
                 .Doc("number of boxes"));
    a->Visit(AIA_FIELD(min_size)
                 .In(kLength)
                 .Shape("[width, height]")
                 .Doc("smallest box, metres"));
    a->Visit(AIA_FIELD(max_size)
                 .In(kLength)
                 .Shape("[width, height]")
                 .Doc("largest box, metres; sizes are uniform in between"));
  }
  void Validate(const FieldChecker& check);
};

struct BoxConfig {
  Vec2 center{0.0, 0.0};
  Vec2 size{1.0, 1.0};

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(center)
                 .In(kCoordinate)
                 .Doc("metres; the box must overlap the workspace"));
    a->Visit(
        AIA_FIELD(size).In(kLength).Shape("[width, height]").Doc("metres"));
  }
};

// The structured worlds of workspace.obstacles.generator (docs/scenarios.md,
// "Generated worlds").
enum class GeneratorType { kMaze, kRooms, kCorridors, kCave };
constexpr std::array<EnumName<GeneratorType>, 4> EnumNames(GeneratorType) {
  return {{{GeneratorType::kMaze, "maze"},
           {GeneratorType::kRooms, "rooms"},
           {GeneratorType::kCorridors, "corridors"},
           {GeneratorType::kCave, "cave"}}};
}
// The name a type is written with ("maze").
const char* GeneratorTypeName(GeneratorType type);

// Whole lattice steps in a length (a length a hair short of a multiple of
// the step counts as that multiple): the unit of generated worlds.
inline int StepsIn(double length, double step) {
  return static_cast<int>(std::floor(length / step + 1e-9));
}

// A seeded structured world that fills the workspace, laid out on the
// robots.step lattice (world/generator.h): widths are whole steps, thin walls
// stand on the lines between lattice points, cave rock fills whole lattice
// cells. One flat set of parameters; each type reads the ones it needs and
// ignores the others (so that effective.yaml, which writes them all, reads
// back, and --set can switch the type).
struct GeneratorConfig {
  GeneratorType type = GeneratorType::kMaze;  // required
  double wall = 0.1;
  double corridor = 2.0;
  double door = 1.0;
  Vec2 room_size{3.0, 8.0};
  double loops = 0.1;
  double fill = 0.44;
  int smoothing = 4;
  double cell = 0.5;

  // Whether the type draws thin walls (maze, rooms, corridors), uses
  // corridors (maze, corridors), doors and rooms (rooms, corridors).
  bool HasWalls() const { return type != GeneratorType::kCave; }
  bool HasCorridors() const {
    return type == GeneratorType::kMaze || type == GeneratorType::kCorridors;
  }
  bool HasRooms() const {
    return type == GeneratorType::kRooms || type == GeneratorType::kCorridors;
  }

  // The rooms' min and max side in lattice steps, and the rooms generator's
  // rule for a part `length` steps across: it is split across that side
  // only where it is longer than max and holds two rooms of min (one rule
  // for the generator and the scenario's check of it).
  struct RoomSteps {
    int min, max;
    bool Splits(int length) const { return length > max && length >= 2 * min; }
  };
  RoomSteps RoomStepsAt(double step) const {
    const int m = std::max(1, StepsIn(room_size.x(), step));
    return {m, std::max(m, StepsIn(room_size.y(), step))};
  }

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(type)
                 .Required("the kind of world: maze, rooms, corridors or cave")
                 .Doc("maze: a spanning-tree maze with some loops; rooms: an "
                      "office split into rooms, one door per split; "
                      "corridors: corridors lined with rooms, joined by cross "
                      "corridors; cave: a cellular-automaton cave"));
    a->Visit(AIA_FIELD(wall).In(kLength).Doc(
        "maze, rooms, corridors: wall thickness, metres; below robots.step - "
        "2 robots.radius (walls stand between lattice points), for "
        "diff_drive robots below robots.step - 2 (robots.radius + "
        "physics.tolerance)"));
    a->Visit(AIA_FIELD(corridor).In(kLength).Doc(
        "maze: passage width; corridors: corridor width; metres, rounded "
        "down to whole robots.step, at least one; maze: two cells of it fit "
        "across the workspace each way"));
    a->Visit(AIA_FIELD(door).In(kLength).Doc(
        "rooms, corridors: door width, metres, rounded down to whole "
        "robots.step, at least one"));
    a->Visit(AIA_FIELD(room_size)
                 .In(kLength)
                 .Shape("[min, max]")
                 .Doc("rooms, corridors: side of a room, metres, rounded down "
                      "to whole robots.step; max at least twice min, min at "
                      "least door; rooms: min at most the workspace's shorter "
                      "side"));
    a->Visit(AIA_FIELD(loops).In(kUnit).Doc(
        "maze: share of the walls left by the spanning tree that are opened "
        "too (0: a perfect maze, one path between any two points)"));
    a->Visit(AIA_FIELD(fill).In(kUnit).Doc(
        "cave: share of rock cells drawn before smoothing (above about 0.5 "
        "the open space breaks apart)"));
    a->Visit(AIA_FIELD(smoothing)
                 .In(Between(0, 100))
                 .Doc("cave: smoothing passes (a cell becomes rock when 5 or "
                      "more of the 9 around it, itself included, are)"));
    a->Visit(AIA_FIELD(cell).In(kLength).Doc(
        "cave: cell of the automaton, metres, rounded down to whole "
        "robots.step (at least one)"));
  }
  // room_size's min is at most its max.
  void Validate(const FieldChecker& check);
};

// Random boxes, explicit boxes and a map image may be combined; a generator
// takes the whole workspace and stands alone.
struct ObstaclesConfig {
  std::optional<RandomObstaclesConfig> random;
  std::vector<BoxConfig> boxes;
  std::string map;  // absolute path of a PGM/PNG image, or empty
  double map_threshold = 0.5;
  std::optional<GeneratorConfig> generator;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(random).Doc(
        "axis-aligned boxes of uniform random size placed uniformly in the "
        "workspace, kept at least robots.radius + robots.step away from "
        "placed robot starts and targets (an empty `random:` takes the "
        "defaults)"));
    a->Visit(AIA_FIELD(boxes).Doc("explicit boxes"));
    a->Visit(AIA_FIELD(map).Path().Doc(
        "PGM or PNG image scaled to the workspace, row 0 at the top; dark "
        "runs are merged into boxes (read as grey: white is a PGM's maximum "
        "value, colour is its luminance, a PNG's transparency is ignored)"));
    a->Visit(AIA_FIELD(map_threshold)
                 .In(kOpenUnit)
                 .Doc("map pixels darker than this fraction of white are "
                      "occupied"));
    a->Visit(AIA_FIELD(generator).Doc(
        "a seeded structured world (maze, rooms, corridors, cave) filling the "
        "workspace, drawn from the scenario seed; its free space is "
        "connected for the robots; not combined with random boxes, boxes or "
        "map"));
  }
  // The map exists and is a file (it is decoded when the world is built); a
  // generator comes without the other sources.
  void Validate(const FieldChecker& check);
};

struct WorkspaceConfig {
  Vec2 size{20.0, 20.0};
  double cell = 0.1;
  ObstaclesConfig obstacles;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(size)
                 .In(Between(0.1, limits::kMaxLength))
                 .Shape("[width, height]")
                 .Doc("metres"));
    a->Visit(AIA_FIELD(cell).In(kLength).Doc(
        "occupancy-grid cell, metres; at most 5e7 cells"));
    a->Visit(AIA_FIELD(obstacles));
  }
  void Validate(const FieldChecker& check);
};

// How a robot's body moves (docs/design.md, Physics).
enum class RobotModel {
  // A disc on two slide joints pulled to its waypoint by a critically damped
  // spring: MuJoCo decides only whether it bumps.
  kPoint,
  // A wheeled body under gravity: two driven wheels on hinge joints, two
  // ball casters, friction with the floor; a low-level controller turns it
  // toward its waypoint and drives (sim/diff_drive.h).
  kDiffDrive,
};
constexpr std::array<EnumName<RobotModel>, 2> EnumNames(RobotModel) {
  return {
      {{RobotModel::kPoint, "point"}, {RobotModel::kDiffDrive, "diff_drive"}}};
}

// A differential-drive robot's body, motors and waypoint controller
// (robots.model: diff_drive). The body's defaults are those of Kobuki, the
// base of TurtleBot 2 (wheel radius 35 mm, wheel base 230 mm, 2.35 kg, top
// speed 0.7 m/s, 180 deg/s, a caster in front and one behind), but for its
// footprint, which is the disc robots.radius so that the lattice stays the
// same; the motor torque and the controller's gains are ours. Read only when
// robots.model is diff_drive (effective.yaml writes them always, so that it
// reads back and --set can switch the model).
// A diff_drive wheel's half width, metres.
inline constexpr double kDiffDriveWheelHalfWidth = 0.01;

struct DiffDriveConfig {
  double wheel_radius = 0.035;
  double track = 0.23;
  double mass = 2.35;
  double height = 0.1;
  double max_speed = 0.7;
  double max_turn_rate = 180.0;
  double max_torque = 0.12;
  double friction = 0.8;
  double speed_gain = 8.0;
  double heading_gain = 4.0;
  double drive_angle = 20.0;
  bool reverse = true;
  std::optional<double> start_heading;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(wheel_radius)
                 .In(Between(0.005, 1.0))
                 .Doc("driven wheels' radius, metres; at most the chassis' "
                      "height"));
    a->Visit(AIA_FIELD(track)
                 .In(Between(0.01, 10.0))
                 .Doc("distance between the two driven wheels, metres; the "
                      "wheels (2 cm wide) sit inside the disc: track / 2 + "
                      "0.01 below robots.radius"));
    a->Visit(AIA_FIELD(mass)
                 .In(Between(0.01, 1e3))
                 .Doc("the whole robot, kg (each wheel 5 % of it)"));
    a->Visit(AIA_FIELD(height)
                 .In(Between(0.01, 10.0))
                 .Doc("chassis top above the floor, metres"));
    a->Visit(AIA_FIELD(max_speed)
                 .In(Between(1e-3, 100.0))
                 .Doc("top speed of a wheel's rim, m/s (the wheel speed "
                      "limit times wheel_radius)"));
    a->Visit(AIA_FIELD(max_turn_rate)
                 .In(Between(1.0, 1e4))
                 .Doc("fastest turn the controller asks for, degrees/s"));
    a->Visit(AIA_FIELD(max_torque)
                 .In(Between(1e-4, 1e3))
                 .Doc("a wheel motor's torque limit, N m"));
    a->Visit(AIA_FIELD(friction)
                 .In(Between(0.01, 10.0))
                 .Doc("sliding friction of the wheels on the floor (the "
                      "casters roll freely)"));
    a->Visit(AIA_FIELD(speed_gain)
                 .In(Between(0.01, 1e3))
                 .Doc("controller: forward speed per metre to the waypoint, "
                      "1/s (also capped by braking at max_torque)"));
    a->Visit(AIA_FIELD(heading_gain)
                 .In(Between(0.01, 1e3))
                 .Doc("controller: turn rate per radian of heading error, "
                      "1/s"));
    a->Visit(AIA_FIELD(drive_angle)
                 .In(Between(1.0, 90.0))
                 .Doc("controller: it drives only while its heading is within "
                      "this of the waypoint's bearing (degrees), else it turns "
                      "in place"));
    a->Visit(AIA_FIELD(reverse).Doc(
        "controller: a waypoint behind the robot is reached backward"));
    a->Visit(AIA_FIELD(start_heading)
                 .In(Between(-360.0, 360.0))
                 .Doc("every robot's heading at the start, degrees from +x "
                      "counter-clockwise; none: a random heading per robot "
                      "(stream robots.heading)"));
  }
  void Validate(const FieldChecker& check);
};

struct RobotsConfig {
  int count = 0;  // required
  double radius = 0.15;
  double step = 0.5;
  std::vector<Vec2> start;  // empty: random free lattice points
  RobotModel model = RobotModel::kPoint;
  DiffDriveConfig diff_drive;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(count)
                 .In(Between(1, limits::kMaxBodies))
                 .Required("the number of robots, an integer >= 1")
                 .Doc("number of robots"));
    a->Visit(AIA_FIELD(radius).In(kLength).Doc(
        "robot disc, metres; below step / 2"));
    a->Visit(AIA_FIELD(step).In(kLength).Doc(
        "lattice spacing and move length, metres; lattice points sit at "
        "(i + 0.5) step; at most 1e6 points"));
    a->Visit(AIA_FIELD(start).Doc(
        "one [x, y] per robot, each snapped to its nearest lattice point "
        "(free, not shared); none: distinct random free points of the "
        "largest connected region"));
    a->Visit(AIA_FIELD(model).Doc(
        "point: a disc on slide joints pulled to its waypoint; diff_drive: a "
        "wheeled body driven by its motors (robots.diff_drive)"));
    a->Visit(AIA_FIELD(diff_drive)
                 .Doc("the diff_drive model's body, motors and controller"));
  }
  void Validate(const FieldChecker& check);
};

struct TargetConfig {
  Vec2 position{0.0, 0.0};
  Vec2 velocity{0.0, 0.0};            // used when the state has dimension 4
  std::optional<Vec2> prior_mean;     // none: truth plus a draw
  std::optional<double> prior_sigma;  // none: TargetsConfig::prior_sigma
  TargetModel dynamics;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(position)
                 .Required("the target's true position [x, y]")
                 .Doc("true initial position"));
    a->Visit(AIA_FIELD(velocity)
                 .In(kCoordinate)
                 .Shape("[vx, vy]")
                 .Doc("true initial velocity; only with 4x4 dynamics"));
    a->Visit(AIA_FIELD(prior_mean)
                 .In(kCoordinate)
                 .Doc("mu_0's position; none: the truth plus N(0, "
                      "prior_offset^2 I) (a 4-D target's velocity mean is "
                      "drawn so either way)"));
    a->Visit(AIA_FIELD(prior_sigma)
                 .In(kPriorSigma)
                 .Doc("prior std; none: targets.prior_sigma"));
    a->Visit(AIA_FIELD(dynamics).Doc("static when not given"));
  }
  void Validate(const FieldChecker& check);
};

struct TargetsConfig {
  int count = 0;  // random static targets (when `list` is empty)
  std::vector<TargetConfig> list;
  double prior_sigma = 1.0;
  double prior_offset = 0.5;

  int Num() const {
    return list.empty() ? count : static_cast<int>(list.size());
  }

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(count)
                 .In(Between(0, limits::kMaxBodies))
                 .Doc("random static targets, each in free space and "
                      "observable (within 0.9 "
                      "of the range, in sight) from a point the robots can "
                      "reach; with "
                      "`list` it must equal the list's length"));
    a->Visit(AIA_FIELD(list).Doc("explicit targets"));
    a->Visit(AIA_FIELD(prior_sigma)
                 .In(kPriorSigma)
                 .Doc("prior std per coordinate: Sigma_0 = prior_sigma^2 I"));
    a->Visit(
        AIA_FIELD(prior_offset)
            .In(Between(0, limits::kMaxLength))
            .Doc(
                "std of a default prior mean around the truth: mu_0 = x + N(0, "
                "prior_offset^2 I), redrawn until it lies in free space where "
                "a reachable lattice point sees it, up to 20 draws; after 20 "
                "misses mu_0 is the truth itself (so an offset far beyond the "
                "workspace gives most targets a perfect prior mean)"));
  }
  // count and list agree; at least one target.
  void Validate(const FieldChecker& check);
};

// When robots decide (SPEC 14).
enum class Decisions {
  // The paper's: every robot decides at once, and a step ends when the
  // team's slowest robot has arrived, stalled or timed out.
  kLockstep,
  // Each robot decides when its own move ends (arrived, stalled or timed
  // out) while the others keep moving; sensing, the graph and the filter
  // update on the physics clock at sensor.rate.
  kAsync,
};
constexpr std::array<EnumName<Decisions>, 2> EnumNames(Decisions) {
  return {{{Decisions::kLockstep, "lockstep"}, {Decisions::kAsync, "async"}}};
}

// How robots deciding asynchronously keep out of each other's way.
enum class Avoidance {
  // None: a robot drives to its next point whoever is there.
  kNone,
  // Each robot holds its lattice point and the point it drives to; a robot
  // whose next point is held waits at its own (yielding) until that point
  // is free, or until the next sensing tick, when it decides again. A
  // point is let go once its robot is 2 radii away from it.
  kReserve,
};
constexpr std::array<EnumName<Avoidance>, 2> EnumNames(Avoidance) {
  return {{{Avoidance::kNone, "none"}, {Avoidance::kReserve, "reserve"}}};
}

struct MissionConfig {
  double eps = 0.1;
  int max_steps = 400;
  bool stop_at_success = true;
  Decisions decisions = Decisions::kLockstep;
  // none given: reserve (async only).
  std::optional<Avoidance> avoidance;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(eps)
                 .In(Between(1e-30, 1e30))
                 .Doc("success: every target has some active robot with det "
                      "Sigma <= eps"));
    a->Visit(AIA_FIELD(max_steps)
                 .In(Between(1, limits::kMaxSteps))
                 .Doc("decision steps at most (--max-steps)"));
    a->Visit(
        AIA_FIELD(stop_at_success)
            .Doc("false: a tracking mission runs its whole horizon, scored by "
                 "localized_share"));
    a->Visit(AIA_FIELD(decisions).Doc(
        "lockstep (the paper's: the team decides together, a step lasts "
        "until its slowest robot is done) or async (each robot decides when "
        "its own move ends; sensing at sensor.rate; steps count the slowest "
        "robot's decisions)"));
    a->Visit(AIA_FIELD(avoidance).Unset("reserve").Doc(
        "async only (refused in lockstep). reserve (a robot "
        "waits while its next lattice point is held by another "
        "robot, there or driving to it, deciding again at the "
        "next sensing tick if it stays held) or none (it "
        "drives on)"));
  }
};

struct PolicyConfig {
  std::string name = "greedy";
  std::string model;  // absolute path, for learned policies
  // SHA-256 of the model file's bytes, as effective.yaml records it; when
  // given, a model file with other content is refused.
  std::optional<std::string> model_sha256;
  // The named policy's parameters as written; the policy registry reads and
  // checks them against the policy's declared parameters (`aia policies`).
  ConfigNode params;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(name)
                 .NonEmpty()
                 .Expect("a policy name such as greedy")
                 .Doc("the decision maker (`aia policies`); --policy"));
    a->Visit(AIA_FIELD(model).Path().Doc("model file of learned policies"));
    a->Visit(AIA_FIELD(model_sha256)
                 .Doc("SHA-256 of the model file (64 hex digits, as sha256sum "
                      "prints it; effective.yaml records it): a model file "
                      "with other content is refused"));
    a->Visit(AIA_FIELD(params).Rest().Doc(
        "the named policy's parameters, listed by `aia policies`"));
  }
  // model_sha256 is 64 lower-case hex digits.
  void Validate(const FieldChecker& check);
};

// MuJoCo's constraint solver (physics.solver). Newton converges in a few
// iterations but MuJoCo 2.2 gives it dense nv x nv work arrays; CG needs
// none but takes about three times as long per step for wheeled robots.
enum class PhysicsSolver { kAuto, kNewton, kCg };
constexpr std::array<EnumName<PhysicsSolver>, 3> EnumNames(PhysicsSolver) {
  return {{{PhysicsSolver::kAuto, "auto"},
           {PhysicsSolver::kNewton, "newton"},
           {PhysicsSolver::kCg, "cg"}}};
}
// auto takes Newton while its work arrays fit in this many bytes.
inline constexpr double kAutoNewtonBytes = 256.0 * (1 << 20);

// physics.step_timeout when the scenario gives none: a wheeled robot turns
// and accelerates, so its steps take longer than a point robot's.
inline constexpr double kPointStepTimeout = 1.0;
inline constexpr double kDiffDriveStepTimeout = 4.0;

// sensor.rate (Hz, async decisions) when the scenario gives none: the
// sensor does not depend on the base; 5 Hz is one tick per point robot's
// lattice move (0.2 s), so that targets, which take a step of their
// dynamics per tick, move as fast in seconds as in the paper's steps, and a
// robot that arrives decides on beliefs at most 0.2 s old.
inline constexpr double DefaultSensorRate(RobotModel /*model*/) { return 5.0; }
// Physics steps from one sensing tick to the next (async): a tick falls on a
// physics step, so the rate's period is rounded to whole steps, at least
// one (at most 1 / timestep ticks a second).
inline long SensingTickSteps(double rate, double timestep) {
  return std::max(1L, std::lround(1.0 / (rate * timestep)));
}
// mission.avoidance (async decisions) when the scenario gives none.
inline constexpr Avoidance kDefaultAvoidance = Avoidance::kReserve;

struct PhysicsConfig {
  // The stall rule (sim/simulation.h): a robot that has not arrived is
  // blocked once it moves slower than kStallSpeed (m/s), from kSettleTime
  // (s) into its move on.
  static constexpr double kStallSpeed = 0.01;
  static constexpr double kSettleTime = 0.05;

  double timestep = 0.005;
  double kp = 200.0;
  double robot_mass = 0.25;
  double tolerance = 0.01;
  std::optional<double> step_timeout;  // none: the robot model's
  PhysicsSolver solver = PhysicsSolver::kAuto;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(timestep)
                 .In(Between(1e-5, 0.1))
                 .Doc("MuJoCo timestep, seconds"));
    a->Visit(AIA_FIELD(kp)
                 .In(Between(1e-3, 1e6))
                 .Doc("point robots: waypoint spring stiffness, N/m "
                      "(critically damped); timestep * sqrt(kp / robot_mass) "
                      "at most 0.5, and a move (one step to within "
                      "tolerance) within about step_timeout"));
    a->Visit(AIA_FIELD(robot_mass)
                 .In(Between(1e-3, 1e3))
                 .Doc("point robots: kg (diff_drive: robots.diff_drive.mass)"));
    a->Visit(AIA_FIELD(tolerance)
                 .In(Between(1e-6, 1.0))
                 .Doc("a robot has arrived within this distance of its "
                      "waypoint, metres; below robots.step / 2"));
    a->Visit(AIA_FIELD(step_timeout)
                 .In(Between(1e-3, 1e3))
                 .Doc("simulated seconds a decision step may last; at most "
                      "1e6 timesteps; point robots: at least 3/4 of a move "
                      "(the spring's time from one lattice point to within "
                      "tolerance of the next); none: 1 for point robots, 4 "
                      "for diff_drive"));
    a->Visit(AIA_FIELD(solver).Doc(
        "MuJoCo's constraint solver: newton, cg, or auto (Newton while its "
        "dense nv x nv work arrays fit in 256 MiB, about 400 diff_drive "
        "robots; else CG, about 3x slower per step)"));
  }
  // step_timeout, or the robot model's default.
  double StepTimeout(RobotModel model) const {
    if (step_timeout) return *step_timeout;
    return model == RobotModel::kDiffDrive ? kDiffDriveStepTimeout
                                           : kPointStepTimeout;
  }
  // Seconds a point robot's waypoint spring takes from rest to within
  // tolerance of a waypoint `step` metres away.
  double PointArrivalSeconds(double step) const;
  // The tolerance is below half a lattice step; a point robot's spring is
  // stable at this timestep, moves faster than the stall speed from
  // kSettleTime until it is within tolerance, and its move fits in a
  // decision step; a decision step is at most 1e6 timesteps. Called by
  // Scenario::Validate, which knows the robot model and robots.step.
  void Validate(const FieldChecker& check, RobotModel model, double step);
};

struct RenderConfig {
  int width = 640;
  int height = 480;
  int fps = 30;
  int follow_robot = -1;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(width)
                 .In(Between(16, 8192))
                 .Doc("video width, pixels (even, 16 to 8192; width x "
                      "height needs 512 MiB + 256 bytes per pixel, within "
                      "aia render --memory-budget)"));
    a->Visit(AIA_FIELD(height)
                 .In(Between(16, 8192))
                 .Doc("video height, pixels (even, 16 to 8192)"));
    a->Visit(AIA_FIELD(fps)
                 .In(Between(1, 1000))
                 .Doc("frames per second of simulated time, at most 1 / "
                      "physics.timestep"));
    a->Visit(
        AIA_FIELD(follow_robot)
            .In(AtLeast(-1))
            .Doc(
                "robot whose uncertainty heatmap `aia render` draws; -1 none"));
  }
  // Even sides (H.264's 4:2:0), checked wherever a scenario is read, so that
  // a run's effective.yaml can always be rendered.
  void Validate(const FieldChecker& check);
};

// One mission. `file` and `sources` let later stages (the world, the policy
// registry) report errors at the line of the offending key.
struct Scenario {
  std::string name = "scenario";
  std::uint64_t seed = 0;
  WorkspaceConfig workspace;
  RobotsConfig robots;
  SensorModel sensor;
  TargetsConfig targets;
  MissionConfig mission;
  CommParams communication;
  PolicyConfig policy;
  PhysicsConfig physics;
  RenderConfig render;

  std::string file;    // the YAML file it came from ("" if built in code)
  KeySources sources;  // where each key came from (lines, --set flags)
  // "FILE:LINE: key: what" for keys given values that nothing reads where
  // they stand (a range with a full graph); the read stores them, commands
  // print them (ReportWarnings, loader.h).
  std::vector<std::string> warnings;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(name).Doc("label used in outputs"));
    a->Visit(AIA_FIELD(seed).Doc(
        "seed of every random stream (obstacles, starts, targets, priors, "
        "sensor noise, packet loss, policies); --seed"));
    a->Visit(AIA_FIELD(workspace));
    a->Visit(AIA_FIELD(robots));
    a->Visit(AIA_FIELD(sensor));
    a->Visit(AIA_FIELD(targets));
    a->Visit(AIA_FIELD(mission));
    a->Visit(AIA_FIELD(communication));
    a->Visit(AIA_FIELD(policy));
    a->Visit(AIA_FIELD(physics));
    a->Visit(AIA_FIELD(render));
  }
  // Checks across sections: positions inside the workspace, robot indices
  // below robots.count, random boxes no larger than the workspace.
  void Validate(const FieldChecker& check);

  int NumTargets() const { return targets.Num(); }
  // The file errors name: `file`, or "(generated scenario)".
  std::string ErrorFile() const {
    return file.empty() ? "(generated scenario)" : file;
  }
  // The error about `key`, at its line (or its nearest given parent's), or
  // naming the command-line flag that set it.
  InputError ErrorAt(const std::string& key, const std::string& what) const;
  // Line of a key, or of its nearest given parent, or 0.
  int LineOf(const std::string& key) const;
};

}  // namespace aia

#endif  // AIA_SCENARIO_CONFIG_H_
