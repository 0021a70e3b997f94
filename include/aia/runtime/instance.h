// One mission instance: the scenario, the world built from it and its
// compiled physics model. Built once and shared, read-only, by every episode
// on it (the runs of several policies on one eval instance, the expert's
// plan for F*), so that the world is generated and MuJoCo compiles once.
#ifndef AIA_RUNTIME_INSTANCE_H_
#define AIA_RUNTIME_INSTANCE_H_

#include <memory>

#include "aia/scenario/config.h"
#include "aia/sim/simulation.h"
#include "aia/world/world.h"

namespace aia {

struct Instance {
  Scenario scenario;
  World world;
  std::shared_ptr<const PhysicsModel> physics;
};

// Builds the world and compiles its model. InputError for invalid scenarios.
std::shared_ptr<const Instance> BuildInstance(const Scenario& scenario);

}  // namespace aia

#endif  // AIA_RUNTIME_INSTANCE_H_
