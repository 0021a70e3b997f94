#include "aia/world/mjcf.h"

#include <langinfo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "aia/core/error.h"

namespace aia {
namespace {

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

// Text as the value of an XML attribute in double quotes: the scenario's
// name may hold any of & < > " ' (a quote ended the attribute, and MuJoCo
// refused the model: issue 37). The loader refuses control characters;
// one that reaches here (a scenario built in code) becomes a space, since
// XML 1.0 has no way to write most of them.
std::string XmlAttribute(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? ' ' : c;
    }
  }
  return out;
}

// An angle to the full precision of a double, so that the heading MuJoCo
// reads is the one drawn.
std::string Angle(double radians) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.17g", radians);
  return buf;
}

// A disc on two damped slide joints; the simulation's spring pulls it.
void WritePointRobot(const World& world, const Scenario& s, int i,
                     std::ostringstream* out) {
  std::ostringstream& x = *out;
  const double mass = s.physics.robot_mass;
  const double damping = 2.0 * std::sqrt(s.physics.kp * mass);  // critical
  const Vec2 p = world.map.lattice().Point(world.robot_starts[i]);
  const auto c = RobotColor(i);
  // qpos (and the controller's target) are displacements from the start,
  // so that the file at rest holds every robot at its start in MuJoCo's
  // own tools.
  x << "    <body name=\"robot" << i << "\" pos=\"" << Num(p.x()) << " "
    << Num(p.y()) << " " << Num(kRobotHalfHeight + 0.001) << "\">\n"
    << "      <joint name=\"robot" << i
    << "_x\" type=\"slide\" axis=\"1 0 0\" damping=\"" << Num(damping)
    << "\"/>\n"
    << "      <joint name=\"robot" << i
    << "_y\" type=\"slide\" axis=\"0 1 0\" damping=\"" << Num(damping)
    << "\"/>\n"
    << "      <geom type=\"cylinder\" size=\"" << Num(world.map.robot_radius())
    << " " << Num(kRobotHalfHeight) << "\" mass=\"" << Num(mass) << "\" rgba=\""
    << c[0] << " " << c[1] << " " << c[2] << " 1\" group=\"" << kGroupAgent
    << "\"/>\n"
    << "    </body>\n";
}

// A wheeled body on a free joint (docs/design.md, Physics): the chassis disc
// (the only part that meets obstacles and other robots), a ball caster in
// front and one behind (frictionless: they take their own condim through
// their priority), and two wheels on hinge joints about the body's y axis,
// whose damping is the motors' velocity loop (the simulation adds the
// drive torque). The body frame sits on the wheels' axle, x forward, y to
// the left wheel. Wheels and casters touch only the floor (contype 2); the
// chassis touches obstacles and chassis (contype 1).
void WriteDiffDriveRobot(const World& world, const Scenario& s, int i,
                         std::ostringstream* out) {
  std::ostringstream& x = *out;
  const DiffDriveConfig& d = s.robots.diff_drive;
  const double radius = world.map.robot_radius();
  const DiffDriveBody b = DiffDriveBodyOf(d, radius);
  const Vec2 p = world.map.lattice().Point(world.robot_starts[i]);
  const double heading = world.robot_headings[i];
  const auto c = RobotColor(i);
  const std::string rgba = Num(c[0]) + " " + Num(c[1]) + " " + Num(c[2]);
  const double r = d.wheel_radius;
  const double chassis_half = 0.5 * (d.height - b.chassis_bottom);
  const double chassis_z = b.chassis_bottom + chassis_half - r;
  const std::string name = "robot" + std::to_string(i);
  x << "    <body name=\"" << name << "\" pos=\"" << Num(p.x()) << " "
    << Num(p.y()) << " " << Num(r) << "\" euler=\"0 0 " << Angle(heading)
    << "\">\n"
    << "      <freejoint name=\"" << name << "_root\"/>\n"
    << "      <geom name=\"" << name << "_chassis\" type=\"cylinder\" size=\""
    << Num(radius) << " " << Num(chassis_half) << "\" pos=\"0 0 "
    << Num(chassis_z) << "\" mass=\"" << Num(b.chassis_mass) << "\" rgba=\""
    << rgba << " 1\" group=\"" << kGroupAgent << "\"/>\n";
  // A dark bar from the centre to the front rim: the heading, seen from
  // above (no mass, no contacts).
  x << "      <geom type=\"box\" size=\"" << Num(0.45 * radius) << " "
    << Num(0.12 * radius) << " 0.002\" pos=\"" << Num(0.5 * radius) << " 0 "
    << Num(d.height - r + 0.002) << "\" mass=\"0\" contype=\"0\" "
    << "conaffinity=\"0\" rgba=\"0.1 0.1 0.1 1\" group=\"" << kGroupAgent
    << "\"/>\n";
  for (const double side : {1.0, -1.0}) {
    x << "      <geom type=\"sphere\" size=\"" << Num(b.caster_radius)
      << "\" pos=\"" << Num(side * b.caster_offset) << " 0 "
      << Num(b.caster_radius - r) << "\" mass=\"0\" condim=\"1\" "
      << "priority=\"1\" contype=\"2\" conaffinity=\"0\" rgba=\"0.2 0.2 "
         "0.2 1\" group=\""
      << kGroupAgent << "\"/>\n";
  }
  for (const char* wheel : {"left", "right"}) {
    const double y = (wheel[0] == 'l' ? 0.5 : -0.5) * d.track;
    // Contact through a sphere of the wheel's radius (one contact point);
    // drawn as a cylinder.
    x << "      <body name=\"" << name << "_" << wheel << "\" pos=\"0 "
      << Num(y) << " 0\">\n"
      << "        <joint name=\"" << name << "_" << wheel
      << "\" type=\"hinge\" axis=\"0 1 0\" damping=\"" << Num(b.wheel_damping)
      << "\"/>\n"
      << "        <geom type=\"sphere\" size=\"" << Num(r) << "\" mass=\""
      << Num(b.wheel_mass) << "\" friction=\"" << Num(d.friction)
      << " 0.005 0.0001\" contype=\"2\" conaffinity=\"0\" group=\""
      << kGroupWheel << "\"/>\n"
      << "        <geom type=\"cylinder\" size=\"" << Num(r) << " "
      << Num(kDiffDriveWheelHalfWidth)
      << "\" euler=\"1.5707963 0 0\" mass=\"0\" "
      << "contype=\"0\" conaffinity=\"0\" rgba=\"0.15 0.15 0.15 1\" "
         "group=\""
      << kGroupAgent << "\"/>\n"
      << "      </body>\n";
  }
  x << "    </body>\n";
}

}  // namespace

void CheckNumericLocale() {
  // The C library's numbers (printf's, strtod's, MuJoCo's XML reader's)
  // follow LC_NUMERIC; a host that set it to a comma-decimal locale (a
  // Python process after locale.setlocale(locale.LC_ALL, "")) would write
  // 0,005 here and read 0.005 there as 0.
  const char* point = nl_langinfo(RADIXCHAR);  // localeconv is not MT-safe
  if (point == nullptr || std::string(point) != ".")
    throw InputError("locale", 0, "LC_NUMERIC",
                     std::string("this process writes numbers with '") +
                         (point ? point : "") +
                         "' as the decimal point, which MuJoCo's model reader "
                         "and aia's files do not read; set LC_NUMERIC to C "
                         "(Python: locale.setlocale(locale.LC_NUMERIC, 'C'))");
}

SolverChoice ChooseSolver(const Scenario& s, long nv) {
  SolverChoice c;
  if (s.robots.model != RobotModel::kDiffDrive) {
    c.newton = s.physics.solver != PhysicsSolver::kCg;
    c.hessians = c.newton ? kPointHessians : 0;
    return c;
  }
  const double newton_bytes =
      static_cast<double>(kWheeledHessians) * nv * nv * sizeof(double);
  switch (s.physics.solver) {
    case PhysicsSolver::kNewton:
      c.newton = true;
      break;
    case PhysicsSolver::kCg:
      c.newton = false;
      break;
    case PhysicsSolver::kAuto:
      c.newton = newton_bytes <= kAutoNewtonBytes;
      break;
  }
  c.hessians = c.newton ? kWheeledHessians : 0;
  return c;
}

MujocoSizes MujocoSizesFor(long nbody, long nv, long contacts, int hessians,
                           long one_row_contacts) {
  MujocoSizes s;
  s.nconmax = static_cast<int>(std::max(1L, contacts));
  one_row_contacts = std::min<long>(one_row_contacts, s.nconmax);
  s.njmax = static_cast<int>(kRowsPerContact * s.nconmax -
                             (kRowsPerContact - 1) * one_row_contacts);
  const long broad_phase = nbody * (nbody - 1) / 2 + 12 * nbody;
  const long newton = hessians * nv * nv + 40 * nv;
  const long constraints = 24L * s.njmax;
  s.nstack = broad_phase + newton + constraints + 20 * (nbody + nv) + 100000;
  return s;
}

long InitialContacts(int num_robots, RobotModel model) {
  // A diff_drive robot always rests on four points: its wheels and casters.
  const long resting = model == RobotModel::kDiffDrive ? 4L * num_robots : 0;
  return 64 + num_robots / 8 + resting;
}

MujocoModelSizes ModelSizesOf(const World& world, const Scenario& s,
                              long contacts) {
  const int n = world.NumRobots();
  const bool wheeled = s.robots.model == RobotModel::kDiffDrive;
  MujocoModelSizes m;
  // The world body, four walls, the obstacles, robots (a diff_drive robot
  // is three bodies: chassis and wheels) and targets.
  m.nbody = 5L + (wheeled ? 3L : 1L) * n + world.NumTargets() +
            static_cast<long>(world.map.obstacles().size());
  m.nv = (wheeled ? 8L : 2L) * n;
  m.solver = ChooseSolver(s, m.nv);
  // A diff_drive robot's two casters always touch the floor, one row each.
  m.one_row_contacts = wheeled ? 2L * n : 0L;
  m.sizes = MujocoSizesFor(
      m.nbody, m.nv,
      contacts > 0 ? contacts : InitialContacts(n, s.robots.model),
      m.solver.hessians, m.one_row_contacts);
  return m;
}

DiffDriveBody DiffDriveBodyOf(const DiffDriveConfig& c, double radius) {
  DiffDriveBody b;
  b.wheel_mass = 0.05 * c.mass;
  b.chassis_mass = c.mass - 2.0 * b.wheel_mass;
  b.caster_radius = 0.5 * c.wheel_radius;
  b.caster_offset = radius - 1.5 * b.caster_radius;
  b.chassis_bottom = 0.3 * c.wheel_radius;
  // The velocity loop's damping: the inertia a wheel drives when the robot
  // rolls straight (half the robot's mass at the rim, the wheel's own
  // spin), over the loop's time constant.
  const double inertia = 0.5 * c.mass * c.wheel_radius * c.wheel_radius +
                         0.4 * b.wheel_mass * c.wheel_radius * c.wheel_radius;
  b.wheel_damping = inertia / kWheelLoopSeconds;
  return b;
}

double MujocoDataBytes(const MujocoSizes& s, long nv, long nu) {
  const double j = s.njmax, v = static_cast<double>(nv);
  // efc_J, efc_JT, efc_AR as mjtNum and their column indices as int, the
  // actuator moments (nu x nv; none in the generated models) and contacts.
  return 12.0 * (j * j + 2.0 * j * v) + 8.0 * nu * v +
         static_cast<double>(sizeof(double)) * 80 * s.nconmax;
}

std::array<float, 3> RobotColor(int robot) {
  // Golden-ratio hue walk: neighbouring ids get well-separated colours.
  const double h = std::fmod(0.08 + robot * 0.61803398875, 1.0);
  const double s = 0.75, v = 0.9;
  const double c = v * s;
  const double hp = h * 6.0;
  const double x = c * (1.0 - std::fabs(std::fmod(hp, 2.0) - 1.0));
  double r = 0, g = 0, b = 0;
  switch (static_cast<int>(hp) % 6) {
    case 0:
      r = c;
      g = x;
      break;
    case 1:
      r = x;
      g = c;
      break;
    case 2:
      g = c;
      b = x;
      break;
    case 3:
      g = x;
      b = c;
      break;
    case 4:
      r = x;
      b = c;
      break;
    default:
      r = c;
      b = x;
      break;
  }
  const double m = v - c;
  return {static_cast<float>(r + m), static_cast<float>(g + m),
          static_cast<float>(b + m)};
}

std::string MakeMjcf(const World& world, const Scenario& s, long contacts) {
  CheckNumericLocale();
  const int n = world.NumRobots();
  const bool wheeled = s.robots.model == RobotModel::kDiffDrive;
  const double W = world.map.size().x(), H = world.map.size().y();
  const double h = kObstacleHeight / 2;
  std::ostringstream x;
  x << "<mujoco model=\"" << (s.name.empty() ? "aia" : XmlAttribute(s.name))
    << "\">\n";
  x << "  <compiler angle=\"radian\"/>\n";
  const MujocoModelSizes model = ModelSizesOf(world, s, contacts);
  const MujocoSizes& sizes = model.sizes;
  x << "  <option timestep=\"" << Num(s.physics.timestep)
    << (wheeled ? "\" gravity=\"0 0 -9.81\"" : "\" gravity=\"0 0 0\"")
    << (model.solver.newton ? "" : " solver=\"CG\"") << "/>\n";
  x << "  <size njmax=\"" << sizes.njmax << "\" nconmax=\"" << sizes.nconmax
    << "\" nstack=\"" << sizes.nstack << "\"/>\n";
  x << "  <visual>\n    <global offwidth=\"" << s.render.width
    << "\" offheight=\"" << s.render.height << "\" fovy=\"45\"/>\n";
  x << "    <quality shadowsize=\"2048\"/>\n    <map znear=\"0.01\"/>\n  "
       "</visual>\n";
  x << "  <asset>\n"
       "    <texture name=\"floor\" type=\"2d\" builtin=\"checker\" "
       "rgb1=\"0.93 0.93 0.93\" "
       "rgb2=\"0.87 0.87 0.87\" width=\"64\" height=\"64\"/>\n"
    << "    <material name=\"floor\" texture=\"floor\" texrepeat=\""
    << Num(W / 2) << " " << Num(H / 2) << "\"/>\n"
    << "    <material name=\"obstacle\" rgba=\"0.35 0.37 0.42 1\"/>\n"
    << "  </asset>\n";
  x << "  <default>\n"
       "    <geom contype=\"1\" conaffinity=\"1\" friction=\"0.2 0.005 "
       "0.0001\"/>\n"
       "  </default>\n";
  x << "  <worldbody>\n";
  x << "    <light pos=\"" << Num(W / 2) << " " << Num(H / 2) << " "
    << Num(2 * std::max(W, H))
    << "\" dir=\"0 0 -1\" directional=\"true\" diffuse=\"0.6 0.6 0.6\"/>\n";
  x << "    <geom name=\"floor\" type=\"plane\" pos=\"" << Num(W / 2) << " "
    << Num(H / 2) << " 0\" size=\"" << Num(W / 2) << " " << Num(H / 2)
    << " 0.1\" material=\"floor\" "
    // Wheels and casters stand on it; point robots glide above it.
    << (wheeled ? "contype=\"0\" conaffinity=\"2\" group=\""
                : "contype=\"0\" conaffinity=\"0\" group=\"")
    << kGroupFloor << "\"/>\n";
  // Border walls, outside the workspace.
  const double t = 0.1;
  struct Wall {
    double cx, cy, sx, sy;
  };
  const Wall walls[4] = {{W / 2, -t / 2, W / 2 + t, t / 2},
                         {W / 2, H + t / 2, W / 2 + t, t / 2},
                         {-t / 2, H / 2, t / 2, H / 2},
                         {W + t / 2, H / 2, t / 2, H / 2}};
  for (int i = 0; i < 4; ++i) {
    x << "    <body name=\"wall" << i << "\" pos=\"" << Num(walls[i].cx) << " "
      << Num(walls[i].cy) << " " << Num(h) << "\"><geom type=\"box\" size=\""
      << Num(walls[i].sx) << " " << Num(walls[i].sy) << " " << Num(h)
      << "\" material=\"obstacle\" group=\"" << kGroupObstacle
      << "\"/></body>\n";
  }
  for (size_t b = 0; b < world.map.obstacles().size(); ++b) {
    const Box& box = world.map.obstacles()[b];
    const Vec2 c = box.Center(), half = 0.5 * box.Size();
    x << "    <body name=\"obstacle" << b << "\" pos=\"" << Num(c.x()) << " "
      << Num(c.y()) << " " << Num(h) << "\"><geom type=\"box\" size=\""
      << Num(half.x()) << " " << Num(half.y()) << " " << Num(h)
      << "\" material=\"obstacle\" group=\"" << kGroupObstacle
      << "\"/></body>\n";
  }
  if (s.robots.model == RobotModel::kDiffDrive) {
    for (int i = 0; i < n; ++i) WriteDiffDriveRobot(world, s, i, &x);
  } else {
    for (int i = 0; i < n; ++i) WritePointRobot(world, s, i, &x);
  }
  // A target's sphere is a site: a body with a geom, whatever its contype,
  // enters MuJoCo's broad phase (as sites, 1000 targets make mj_step about
  // 3 % faster at 1000 robots).
  for (int k = 0; k < world.NumTargets(); ++k) {
    const Vec2 p = world.TargetStart(k);
    x << "    <body name=\"target" << k << "\" mocap=\"true\" pos=\""
      << Num(p.x()) << " " << Num(p.y())
      << " 0.08\"><site type=\"sphere\" size=\"0.1\" rgba=\""
      << Num(kTargetRgb[0]) << " " << Num(kTargetRgb[1]) << " "
      << Num(kTargetRgb[2]) << " 1\" group=\"" << kGroupAgent
      << "\"/></body>\n";
  }
  x << "  </worldbody>\n";
  // The waypoint controller's stiffness, read by the simulation, which applies
  // kp (waypoint - q) as a force on each slide joint before every mj_step.
  // Position actuators would do the same but cost MuJoCo 2.2 O(N^2) per step
  // (its actuator moments are a dense nu x nv matrix).
  if (!wheeled) {
    x << "  <custom>\n    <numeric name=\"" << kKpNumeric << "\" data=\""
      << Num(s.physics.kp) << "\"/>\n  </custom>\n";
  }
  x << "</mujoco>\n";
  return x.str();
}

}  // namespace aia
