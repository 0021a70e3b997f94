#include "aia/world/mjcf.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace aia {
namespace {

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

}  // namespace

MujocoSizes MujocoSizesFor(long nbody, long nv, long contacts) {
  MujocoSizes s;
  s.nconmax = static_cast<int>(std::max(1L, contacts));
  s.njmax = static_cast<int>(kRowsPerContact * s.nconmax);
  const long broad_phase = nbody * (nbody - 1) / 2 + 12 * nbody;
  const long newton = 3 * nv * nv + 40 * nv;
  const long constraints = 24L * s.njmax;
  s.nstack = broad_phase + newton + constraints + 20 * (nbody + nv) + 100000;
  return s;
}

long InitialContacts(int num_robots) { return 64 + num_robots / 8; }

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
  const int n = world.NumRobots();
  const double W = world.map.size().x(), H = world.map.size().y();
  const double mass = s.physics.robot_mass;
  const double damping = 2.0 * std::sqrt(s.physics.kp * mass);  // critical
  const double h = kObstacleHeight / 2;
  std::ostringstream x;
  x << "<mujoco model=\"" << (s.name.empty() ? "aia" : s.name) << "\">\n";
  x << "  <compiler angle=\"radian\"/>\n";
  x << "  <option timestep=\"" << Num(s.physics.timestep)
    << "\" gravity=\"0 0 0\"/>\n";
  // The world body, four walls, the obstacles, robots and targets.
  const long bodies = 5L + n + world.NumTargets() +
                      static_cast<long>(world.map.obstacles().size());
  const MujocoSizes sizes = MujocoSizesFor(
      bodies, 2L * n, contacts > 0 ? contacts : InitialContacts(n));
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
    << "contype=\"0\" conaffinity=\"0\" group=\"" << kGroupFloor << "\"/>\n";
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
  for (int i = 0; i < n; ++i) {
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
      << "      <geom type=\"cylinder\" size=\""
      << Num(world.map.robot_radius()) << " " << Num(kRobotHalfHeight)
      << "\" mass=\"" << Num(mass) << "\" rgba=\"" << c[0] << " " << c[1] << " "
      << c[2] << " 1\" group=\"" << kGroupAgent << "\"/>\n"
      << "    </body>\n";
  }
  for (int k = 0; k < world.NumTargets(); ++k) {
    const Vec2 p = world.TargetStart(k);
    x << "    <body name=\"target" << k << "\" mocap=\"true\" pos=\""
      << Num(p.x()) << " " << Num(p.y())
      << " 0.08\"><geom type=\"sphere\" size=\"0.1\" rgba=\""
      << Num(kTargetRgb[0]) << " " << Num(kTargetRgb[1]) << " "
      << Num(kTargetRgb[2]) << " 1\" "
      << "contype=\"0\" conaffinity=\"0\" group=\"" << kGroupAgent
      << "\"/></body>\n";
  }
  x << "  </worldbody>\n";
  // The waypoint controller's stiffness, read by the simulation, which applies
  // kp (waypoint - q) as a force on each slide joint before every mj_step.
  // Position actuators would do the same but cost MuJoCo 2.2 O(N^2) per step
  // (its actuator moments are a dense nu x nv matrix).
  x << "  <custom>\n    <numeric name=\"" << kKpNumeric << "\" data=\""
    << Num(s.physics.kp) << "\"/>\n  </custom>\n";
  x << "</mujoco>\n";
  return x.str();
}

}  // namespace aia
