// I-GBNet's network (docs/learning.md, Network): a conv stem, 3 residual
// blocks (Conv3x3-BN-ReLU-Conv3x3-BN, skip, ReLU), adaptive average pooling
// to a fixed pool x pool grid (any workspace size maps to the same size) and
// an MLP to 4 logits, one per move (core/types.h order: left, right, up,
// down). libtorch stays behind this header: only src/learning/network.cc and
// the trainer include it.
#ifndef AIA_LEARNING_NETWORK_H_
#define AIA_LEARNING_NETWORK_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "aia/core/hash.h"
#include "aia/learning/channels.h"

namespace aia {

struct NetworkConfig {
  ChannelParams channels;
  int width = 32;       // feature channels of the stem and the blocks
  int stem_stride = 2;  // the stem's stride (docs/learning.md, Speed)
  int pool = 5;         // P: adaptive pooling to P x P
  int hidden = 128;     // the MLP's hidden units

  // The model file's metadata (JSON), and back; FromJson throws
  // std::runtime_error on anything missing or out of range.
  std::string ToJson() const;
  static NetworkConfig FromJson(const std::string& json);
};

class IgbNet {
 public:
  // A freshly initialized network (libtorch's default initialization,
  // seeded).
  IgbNet(const NetworkConfig& config, std::uint64_t seed);
  ~IgbNet();
  IgbNet(const IgbNet&) = delete;
  IgbNet& operator=(const IgbNet&) = delete;

  // A saved model. A missing file, one that is not a model, or one whose
  // tensors do not match its own metadata is an InputError at
  // (`error_file`, `error_line`, `key`).
  static std::unique_ptr<IgbNet> Load(const std::string& path,
                                      const std::string& error_file,
                                      int error_line, const std::string& key);
  // Writes the model (weights, batch-norm statistics and metadata) to a
  // temporary file and renames it over `path`.
  void Save(const std::string& path) const;

  const NetworkConfig& config() const;
  // The file a loaded model was read from: its absolute path and the
  // SHA-256 of the bytes read (empty for a network made in memory).
  const FileIdentity& file() const;
  // Inference (evaluation mode, no gradients; safe from several threads):
  // `images` holds `batch` images of kNumChannels x height x width floats;
  // writes batch x 4 logits.
  void Forward(const float* images, int batch, int height, int width,
               float* logits) const;
  // Number of trainable parameters.
  std::int64_t NumParameters() const;

  struct Impl;  // the libtorch module (src/learning/network_impl.h)
  // The module to change (training): forgets what Forward folded.
  Impl& impl();
  const Impl& impl() const { return *impl_; }

 private:
  IgbNet();
  std::unique_ptr<Impl> impl_;
};

// Sets libtorch's intra-op threads (0: leave its default).
void SetInferenceThreads(int threads);
int InferenceThreads();

// Threads of the learned policy's rendering and inference (workers of
// ParallelFor; 1 until set; 0 leaves it). Each runs libtorch single-threaded.
void SetPolicyThreads(int threads);
int PolicyThreads();

// Runs f(begin, end, worker) over [0, n) in chunks of `grain` on
// PolicyThreads() threads, worker in [0, PolicyThreads()); libtorch runs
// single-threaded in each (nested OpenMP teams spin against each other on
// two cores). Each index is visited once; what f writes per index must not
// depend on the split.
void ParallelFor(int n, int grain, const std::function<void(int, int, int)>& f);

}  // namespace aia

#endif  // AIA_LEARNING_NETWORK_H_
