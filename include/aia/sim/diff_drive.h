// The low-level controller of a differential-drive robot (robots.model:
// diff_drive; docs/design.md, Physics): turn toward the decided lattice
// waypoint and drive to it, with a feedback law on the heading error and the
// distance under the motors' limits. Plain functions of the robot's pose,
// free of MuJoCo, so that they are checked by hand; the simulation calls
// them before every mj_step.
#ifndef AIA_SIM_DIFF_DRIVE_H_
#define AIA_SIM_DIFF_DRIVE_H_

#include "aia/core/types.h"
#include "aia/scenario/config.h"

namespace aia {

// An angle in (-pi, pi].
double WrapAngle(double a);

// Heading (yaw, radians from +x) of a unit quaternion (w, x, y, z).
double YawOf(const double quat[4]);

// Wheel speeds, rad/s (positive rolls the robot forward).
struct WheelSpeeds {
  double left = 0.0;
  double right = 0.0;
  bool turning = false;  // turning in place: the heading is beyond drive_angle
};

// The law with its constants derived once from the scenario.
class DiffDriveLaw {
 public:
  DiffDriveLaw() = default;
  // `tolerance`: physics.tolerance; the robot stops within a quarter of it.
  DiffDriveLaw(const DiffDriveConfig& config, double tolerance);

  // The heading error the robot must turn through: the bearing of `goal`
  // from `p` less `heading`, or, when it may reverse and the goal lies
  // behind, less the heading of its back. Sets *backward accordingly.
  double HeadingError(const Vec2& p, double heading, const Vec2& goal,
                      bool* backward) const;

  // Within near_radius (5 tolerances, at least 5 cm) of the goal, with the
  // goal within half a tolerance of the robot's axis: the signed distance
  // along the axis to the goal's foot (negative behind); else NaN.
  double AlongTrack(const Vec2& p, double heading, const Vec2& goal) const;

  // Wheel speeds toward `goal` from pose (p, heading). Near the goal and on
  // its axis (AlongTrack) the robot rolls straight, v as below with the
  // distance along the axis, no turn; else
  //   omega = clamp(k_h alpha, +-omega_max),
  //   v = min(v_max, k_d d, sqrt(2 a d)) * max(0, (cos alpha - cos alpha_d)
  //       / (1 - cos alpha_d)), backward when the goal is behind,
  // where alpha is the heading error, d the distance, a the braking
  // deceleration one motor's torque gives, alpha_d robots.diff_drive
  // .drive_angle; then scaled so that no wheel's rim exceeds max_speed,
  // the turn kept first. Zero within the stop radius.
  WheelSpeeds Control(const Vec2& p, double heading, const Vec2& goal) const;

  // Wheel travel left to the goal, metres: the distance plus the arc each
  // wheel rolls to turn through the heading error (the distance alone where
  // it rolls straight, AlongTrack). A robot that has not
  // reduced it is making no progress (stalled), whether it drives or turns.
  double ToGo(const Vec2& p, double heading, const Vec2& goal) const;

  double half_track() const { return half_track_; }
  // The deceleration Speed brakes with, m/s^2.
  double brake() const { return brake_; }
  // min(v_max, k_d d, sqrt(2 a d)): the speed for a distance d.
  double Speed(double distance) const;
  double wheel_radius() const { return wheel_radius_; }

 private:
  double wheel_radius_ = 0.035;
  double half_track_ = 0.115;
  double max_speed_ = 0.7;      // m/s at a wheel's rim
  double max_turn_rate_ = 3.0;  // rad/s
  double brake_ = 1.0;          // m/s^2
  double speed_gain_ = 8.0;     // 1/s
  double heading_gain_ = 4.0;   // 1/s
  double cos_drive_ = 0.866;    // cos(drive_angle)
  double stop_radius_ = 0.0;    // m
  double near_radius_ = 0.05;   // m
  double lateral_slack_ = 0.0;  // m
  bool reverse_ = true;
};

// A wheel motor's drive torque, added to the joint's damping kv (which
// MuJoCo integrates implicitly): kv * omega_ref, clamped so that the motor's
// whole torque kv (omega_ref - omega) stays within +-max_torque at the
// current wheel speed omega.
double MotorTorque(double kv, double omega_ref, double omega,
                   double max_torque);

}  // namespace aia

#endif  // AIA_SIM_DIFF_DRIVE_H_
