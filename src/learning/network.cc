// NetworkConfig's metadata JSON (learning/network.h), read and written by
// both sides of the plugin seam (src/learning/torch_backend.h): no torch.
#include "aia/learning/network.h"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "aia/core/error.h"
#include "aia/core/field_io.h"

namespace aia {
namespace {

constexpr const char* kFormat = "aia-igbnet";
// Version 2: the optional geodesic channel; version 3: message passing
// (each written only when it is on, so that a model without it stays
// readable by older builds); version 4: the reach channel over the world,
// search points and the trail; version 5: the centre; version 6: the reach
// channel's detour (ChannelParams::reach_detour); version 7: the broad reach
// channel (ChannelParams::reach_broad); version 8: the second reach channel
// (ChannelParams::reach_second); version 9: the neighbours channel's cap
// (ChannelParams::neighbour_cap).
constexpr int kVersion = 9;

// Writes declared fields into a JSON object with their own types (an
// integer stays an integer, an enumeration is its name).
class JsonFieldWriter {
 public:
  explicit JsonFieldWriter(nlohmann::json* out) : out_(out) {}
  template <typename T>
  void Visit(const Field<T>& f) {
    if constexpr (std::is_enum_v<T>) {
      for (const auto& n : EnumNames(T{})) {
        if (n.value == *f.value) {
          (*out_)[std::string(f.name)] = n.name;
          break;
        }
      }
    } else {
      (*out_)[std::string(f.name)] = *f.value;
    }
  }

 private:
  nlohmann::json* out_;
};

// A flat JSON object of scalars as a ConfigNode mapping (numbers and
// booleans plain, so that the field reader types them as it does YAML).
ConfigNode ConfigFromJson(const nlohmann::json& j) {
  ConfigNode node = ConfigNode::Map();
  for (const auto& [key, v] : j.items()) {
    ConfigNode value;
    if (v.is_boolean()) {
      value = ConfigNode::Scalar(v.get<bool>() ? "true" : "false");
    } else if (v.is_number_integer()) {
      value = ConfigNode::Scalar(v.dump());
    } else if (v.is_number_float()) {
      value = ConfigNode::Scalar(field_text::ShortestReal(v.get<double>()));
    } else if (v.is_string()) {
      value = ConfigNode::Scalar(v.get<std::string>());
    } else {
      value = ConfigNode::Scalar(v.dump(), ConfigNode::Style::kQuoted);
    }
    node.Set(key, std::move(value));
  }
  return node;
}

}  // namespace

std::string NetworkConfig::ToJson() const {
  nlohmann::json j;
  j["format"] = kFormat;
  const bool world = channels.geodesic && channels.reach_world;
  j["version"] = channels.neighbour_cap > 0             ? 9
                 : world && channels.reach_second       ? 8
                 : world && channels.reach_broad > 0.0  ? 7
                 : world && channels.reach_detour > 0.0 ? 6
                 : centre > 0                           ? 5
                 : world || channels.trail              ? 4
                 : message_hops > 0                     ? 3
                 : channels.geodesic                    ? 2
                                                        : 1;
  JsonFieldWriter writer(&j);
  const_cast<NetworkConfig*>(this)->Serialize(&writer);
  // A feature that is off is not written, so that a model without it keeps
  // the older version (and the bytes older builds wrote).
  if (!channels.geodesic) {
    for (const char* key : {"geodesic", "geodesic_length", "observe_range"})
      j.erase(key);
  }
  if (!channels.geodesic || channels.reach_margin == 0) j.erase("reach_margin");
  if (!world) j.erase("reach_world");
  if (!world || !channels.search) j.erase("search");
  if (!world || channels.reach_detour == 0.0) j.erase("reach_detour");
  if (!world || channels.reach_broad == 0.0) j.erase("reach_broad");
  if (!world || !channels.reach_second) j.erase("reach_second");
  if (!channels.trail) j.erase("trail");
  if (channels.neighbour_cap == 0) j.erase("neighbour_cap");
  if (message_hops == 0) j.erase("message_hops");
  if (centre == 0) j.erase("centre");
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

NetworkConfig NetworkConfig::FromJson(const std::string& text) {
  nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object())
    throw std::runtime_error("its metadata is not JSON");
  if (j.value("format", "") != kFormat)
    throw std::runtime_error("not an aia I-GBNet model");
  if (!j.contains("version"))
    throw std::runtime_error("metadata: version: is missing");
  const nlohmann::json& v = j["version"];
  const bool integer = v.is_number_integer();
  if (!integer || v.get<std::int64_t>() < 1 || v.get<std::int64_t>() > kVersion)
    throw std::runtime_error(
        integer ? "model format version " + v.dump() +
                      ", this build reads 1 to " + std::to_string(kVersion)
                : "metadata: version: must be an integer in [1, " +
                      std::to_string(kVersion) + "], got " +
                      v.dump(-1, ' ', false,
                             nlohmann::json::error_handler_t::replace));
  j.erase("format");
  j.erase("version");
  // What every version writes; the other keys default to "off".
  for (const char* key : {"frame", "cell", "window", "blur", "cutoff", "width",
                          "stem_stride", "pool", "hidden"})
    if (!j.contains(key))
      throw std::runtime_error(std::string("metadata: ") + key +
                               ": is missing");
  NetworkConfig c;
  try {
    ReadOptions options;
    options.file = "metadata";
    ReadFields(ConfigFromJson(j), options, "", &c);
  } catch (const InputError& e) {
    throw std::runtime_error("metadata: " + e.key() + ": " + e.message());
  }
  if (const auto [key, needs] = c.channels.MissingPrerequisite(); !key.empty())
    throw std::runtime_error("metadata: " + std::string(key) + ": needs " +
                             std::string(needs));
  if (const std::string problem = c.CentreProblem(); !problem.empty())
    throw std::runtime_error("metadata: centre: " + problem);
  return c;
}

int NetworkConfig::FeatureSide() const {
  return (channels.window - 1) / stem_stride + 1;
}

int NetworkConfig::CentreStart() const {
  // The robot's pixel is window / 2; output cell j is centred on input
  // pixel stem_stride j.
  const int robot = (channels.window / 2 + stem_stride / 2) / stem_stride;
  return robot - centre / 2;
}

std::string NetworkConfig::CentreProblem() const {
  if (centre == 0) return "";
  if (centre % 2 == 0) return "must be odd (the robot's cell in the middle)";
  if (channels.frame != ChannelFrame::kCentred)
    return "needs the centred frame (frame: centred)";
  if (CentreStart() < 0 || CentreStart() + centre > FeatureSide())
    return "must be at most " +
           std::to_string(
               2 * std::min(CentreStart() + centre / 2,
                            FeatureSide() - 1 - (CentreStart() + centre / 2)) +
               1) +
           ": the blocks' output is " + std::to_string(FeatureSide()) +
           " cells per side";
  return "";
}

}  // namespace aia
