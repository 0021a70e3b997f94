// The seam between learning/ and libtorch: the plugin libaia_torch.so
// (src/learning/torch/) exports one table of plain functions, and IgbNet,
// Train, Validate, MeasureNetworkSpeed and the thread settings call through
// it. The plugin is loaded at the first call that needs it, so that a process
// which never makes or loads a network never loads libtorch (its start costs
// about half a second, most of a bad-input run's time). Plain functions and
// an opaque TorchNet, no virtual calls across the boundary: the two sides
// hold their own copies of aia's libraries, and nothing but this table and
// the values it passes crosses.
#ifndef AIA_SRC_LEARNING_TORCH_BACKEND_H_
#define AIA_SRC_LEARNING_TORCH_BACKEND_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "aia/core/plugin.h"
#include "aia/learning/network.h"
#include "aia/learning/trainer.h"

namespace aia {

// Bumped whenever the table below changes.
inline constexpr int kTorchBackendVersion = 2;
// The plugin's one exported symbol: extern "C" const void* NAME(), its table
// (core/plugin.h).
inline constexpr const char* kTorchBackendSymbol = "aia_torch_backend";

struct TorchBackend {
  PluginHeader header{kTorchBackendVersion, sizeof(TorchBackend)};
  TorchNet* (*create)(const NetworkConfig& config, std::uint64_t seed);
  TorchNet* (*load)(const std::string& path, const std::string& error_file,
                    int error_line, const std::string& key);
  void (*destroy)(TorchNet* net);
  void (*save)(const TorchNet& net, const std::string& path);
  const NetworkConfig& (*config)(const TorchNet& net);
  const FileIdentity& (*file)(const TorchNet& net);
  // Forward (embed false) or Embed (true); the convolutions in bfloat16
  // where `bfloat16` (IgbNet::Forward).
  void (*infer)(const TorchNet& net, const float* images, int batch, int height,
                int width, bool embed, bool bfloat16, float* out);
  void (*head)(const TorchNet& net, const float* features,
               const TeamGraph& graph, float* logits);
  std::int64_t (*num_parameters)(const TorchNet& net);
  std::vector<EpochLog> (*train)(const TrainOptions& options);
  ValidationResult (*validate)(const std::string& model,
                               const std::vector<std::string>& data,
                               double val_share, std::uint64_t seed,
                               bool valid_moves);
  double (*network_speed)(const NetworkConfig& config, int height, int width,
                          int batch, bool train, int iterations, int repeats,
                          bool bf16);
  // torch::set_num_threads (on the calling thread's OpenMP team too) and
  // torch::get_num_threads.
  void (*set_threads)(int threads);
  int (*threads)();
  // Whether inference may run the convolutions on oneDNN's own tensors
  // (torch_net.h, FoldedNet); returns the setting before.
  bool (*set_onednn_layout)(bool on);
  // NativeBFloat16 (network.h).
  bool (*native_bfloat16)();
};

// The plugin's table, loading it at the first call (thread-safe; errors as
// LoadPluginTable's).
const TorchBackend& Torch();
// The table if the plugin is loaded already, else null (nothing is loaded).
const TorchBackend* TorchIfLoaded();

}  // namespace aia

#endif  // AIA_SRC_LEARNING_TORCH_BACKEND_H_
