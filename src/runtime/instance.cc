#include "aia/runtime/instance.h"

namespace aia {

std::shared_ptr<const Instance> BuildInstance(const Scenario& scenario) {
  auto instance = std::make_shared<Instance>();
  instance->scenario = scenario;
  instance->world = World::Build(scenario);
  instance->physics =
      std::make_shared<const PhysicsModel>(instance->world, scenario);
  return instance;
}

}  // namespace aia
