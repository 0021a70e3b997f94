// The range-limited, distance-scaled position sensor (docs/design.md, Sensing):
// y = pos_k - p_i + v, v ~ N(0, R), R = (sigma0 + eta * dist)^2 I.
#ifndef AIA_ESTIMATION_SENSOR_MODEL_H_
#define AIA_ESTIMATION_SENSOR_MODEL_H_

#include <optional>

#include "aia/core/fields.h"
#include "aia/core/types.h"

namespace aia {

// Declared once: the scenario's `sensor:` section and what sensing, the
// filter and the planners use.
struct SensorModel {
  double range = 2.0;
  double eta = 0.05;
  double sigma0 = 0.01;
  bool line_of_sight = true;
  // mission.decisions async only: sensing, the graph and the filter update
  // this often on the physics clock (Hz); none: the robot model's
  // DefaultSensorRate.
  std::optional<double> rate;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(range)
                 .In(Between(1e-3, 1e4))
                 .Doc("sensing range, metres: a target farther away is not "
                      "measured"));
    a->Visit(
        AIA_FIELD(eta)
            .In(Between(0, 1e3))
            .Doc("noise std grows by eta per metre: R = (sigma0 + eta d)^2 I"));
    a->Visit(AIA_FIELD(sigma0)
                 .In(Between(1e-6, 1e4))
                 .Doc("noise std at zero distance, metres"));
    a->Visit(AIA_FIELD(line_of_sight)
                 .Doc("obstacles block sensing (a ray against the obstacles, "
                      "mj_ray)"));
    a->Visit(AIA_FIELD(rate)
                 .In(Between(1e-3, 1e3))
                 .Doc("Hz, mission.decisions async only: how often robots "
                      "sense, the graph and the filter update (and targets "
                      "take a step of their dynamics) on the physics clock, "
                      "a tick every whole number of physics steps (a rate "
                      "that is not is rounded, with a warning; at most 1 / "
                      "physics.timestep); none: 5 (a point robot's lattice "
                      "move takes 0.2 s)"));
  }

  // Noise standard deviation at distance `dist`.
  double Std(double dist) const { return sigma0 + eta * dist; }
  // R^-1 = 1 / (sigma0 + eta * dist)^2, the scalar of the isotropic precision.
  double Precision(double dist) const {
    const double s = Std(dist);
    return 1.0 / (s * s);
  }
  bool InRange(double dist) const { return dist <= range; }
};

// One robot's measurement of one target: y is the measured relative position
// pos_k - p_i + v; precision is the scalar of R^-1 (the filter computes it from
// |y|, the simulator draws v with the true distance).
struct Measurement {
  int target = 0;
  Vec2 y{0.0, 0.0};
  double precision = 0.0;
};

}  // namespace aia

#endif  // AIA_ESTIMATION_SENSOR_MODEL_H_
