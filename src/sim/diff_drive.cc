#include "aia/sim/diff_drive.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace aia {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

double WrapAngle(double a) {
  a = std::remainder(a, 2.0 * kPi);  // [-pi, pi]
  return a <= -kPi ? a + 2.0 * kPi : a;
}

double YawOf(const double q[4]) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
}

DiffDriveLaw::DiffDriveLaw(const DiffDriveConfig& c, double tolerance)
    : wheel_radius_(c.wheel_radius),
      half_track_(0.5 * c.track),
      max_speed_(c.max_speed),
      max_turn_rate_(c.max_turn_rate * kPi / 180.0),
      // Half of what both motors can brake the whole robot with: margin for
      // the casters' drag and the loop's lag.
      brake_(c.max_torque / (c.wheel_radius * c.mass)),
      speed_gain_(c.speed_gain),
      heading_gain_(c.heading_gain),
      cos_drive_(std::cos(c.drive_angle * kPi / 180.0)),
      stop_radius_(0.25 * tolerance),
      near_radius_(std::max(5.0 * tolerance, 0.05)),
      lateral_slack_(0.5 * tolerance),
      reverse_(c.reverse) {}

double DiffDriveLaw::HeadingError(const Vec2& p, double heading,
                                  const Vec2& goal, bool* backward) const {
  const Vec2 e = goal - p;
  double alpha = WrapAngle(std::atan2(e.y(), e.x()) - heading);
  *backward = reverse_ && std::fabs(alpha) > 0.5 * kPi;
  if (*backward) alpha = WrapAngle(alpha - kPi);
  return alpha;
}

double DiffDriveLaw::AlongTrack(const Vec2& p, double heading,
                                const Vec2& goal) const {
  const Vec2 e = goal - p;
  if (e.norm() > near_radius_) return kNaN;
  const Vec2 h(std::cos(heading), std::sin(heading));
  const double along = e.dot(h);
  const double lateral = h.x() * e.y() - h.y() * e.x();
  if (std::fabs(lateral) > lateral_slack_) return kNaN;
  if (along < 0.0 && !reverse_) return kNaN;
  return along;
}

double DiffDriveLaw::Speed(double distance) const {
  return std::min(
      {max_speed_, speed_gain_ * distance, std::sqrt(2.0 * brake_ * distance)});
}

WheelSpeeds DiffDriveLaw::Control(const Vec2& p, double heading,
                                  const Vec2& goal) const {
  const double d = (goal - p).norm();
  if (d <= stop_radius_) return {};
  // On its last centimetres, once the goal lies on its axis, the robot rolls
  // straight to it: the bearing of a goal a few millimetres off would swing
  // with every millimetre and turn the robot for nothing.
  if (const double along = AlongTrack(p, heading, goal); !std::isnan(along)) {
    const double v = std::copysign(Speed(std::fabs(along)), along);
    return {v / wheel_radius_, v / wheel_radius_};
  }
  bool backward = false;
  const double alpha = HeadingError(p, heading, goal, &backward);
  const double omega =
      std::clamp(heading_gain_ * alpha, -max_turn_rate_, max_turn_rate_);
  // Forward speed: the distance's, braking in time, faded out as the
  // heading error grows to drive_angle (turn in place beyond it).
  const double fade =
      std::max(0.0, (std::cos(alpha) - cos_drive_) / (1.0 - cos_drive_));
  double v = Speed(d) * fade;
  // Keep each rim within max_speed: the turn first, then what is left.
  const double turn = std::min(std::fabs(omega) * half_track_, max_speed_);
  v = std::min(v, max_speed_ - turn);
  if (backward) v = -v;
  const double w = std::copysign(turn / half_track_, omega);
  return {(v - w * half_track_) / wheel_radius_,
          (v + w * half_track_) / wheel_radius_, fade == 0.0};
}

double DiffDriveLaw::ToGo(const Vec2& p, double heading,
                          const Vec2& goal) const {
  const double d = (goal - p).norm();
  if (d <= stop_radius_) return d;
  if (!std::isnan(AlongTrack(p, heading, goal))) return d;
  bool backward = false;
  const double alpha = HeadingError(p, heading, goal, &backward);
  return d + half_track_ * std::fabs(alpha);
}

double MotorTorque(double kv, double omega_ref, double omega,
                   double max_torque) {
  return std::clamp(kv * omega_ref, kv * omega - max_torque,
                    kv * omega + max_torque);
}

}  // namespace aia
