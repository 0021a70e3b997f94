// The libtorch side of learning/network.h, inside the plugin libaia_torch.so
// (src/learning/torch/, loaded by src/learning/torch_backend.cc at the first
// use of a network): the network and the trainer. Nothing outside this
// folder includes torch.
#ifndef AIA_SRC_LEARNING_TORCH_TORCH_NET_H_
#define AIA_SRC_LEARNING_TORCH_TORCH_NET_H_

#include <torch/torch.h>

#include <array>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "aia/learning/network.h"
#include "aia/learning/trainer.h"

namespace aia {

struct ResidualBlockImpl : torch::nn::Module {
  explicit ResidualBlockImpl(int width);
  torch::Tensor forward(const torch::Tensor& x);
  torch::nn::Conv2d conv1{nullptr}, conv2{nullptr};
  torch::nn::BatchNorm2d bn1{nullptr}, bn2{nullptr};
};
TORCH_MODULE(ResidualBlock);

// A batch's graph as tensors for message passing: edge e carries row
// src[e]'s features to row dst[e]; inv_degree[b] is 1 / (b's neighbours), 0
// for a robot without any.
struct GraphTensors {
  torch::Tensor src, dst, inv_degree;
};
GraphTensors ToTensors(const TeamGraph& graph);

struct IgbNetModuleImpl : torch::nn::Module {
  explicit IgbNetModuleImpl(const NetworkConfig& config);
  // N x C x H x W -> N x 4, each robot alone.
  torch::Tensor forward(const torch::Tensor& x);
  // The same with message passing over `graph` (its rows are the batch's).
  torch::Tensor forward(const torch::Tensor& x, const GraphTensors& graph);
  // The hidden features z = relu(fc1(pooled stem and blocks)), N x hidden.
  torch::Tensor embed(const torch::Tensor& x);
  // z -> logits: fc2(relu(z + sum_k M_k S^k z)) (fc2(z) without hops).
  torch::Tensor head(const torch::Tensor& z, const GraphTensors* graph);
  torch::nn::Conv2d stem{nullptr};
  torch::nn::BatchNorm2d stem_bn{nullptr};
  torch::nn::ModuleList blocks;
  torch::nn::AdaptiveAvgPool2d pool{nullptr};
  torch::nn::Linear fc1{nullptr}, fc2{nullptr};
  // The centre (NetworkConfig::centre): fc1 reads the pooled grid, then
  // the centre x centre cells from centre_start on (0: none).
  int centre = 0, centre_start = 0;
  // M_1..M_K (hidden x hidden, no bias; `aia train --init` zeroes the hops
  // it adds, so that the extended network starts as the same function);
  // registered only when K > 0, so older model files keep their names.
  std::vector<torch::nn::Linear> messages;
};
TORCH_MODULE(IgbNetModule);

// `to` as the same function as `from`, where it reads more: tensors of the
// same shape are copied; a wider one (the stem with a new last input
// channel, fc1 with the centre's inputs) gets `from`'s part and zeros
// (narrower: `from`'s first part); message layers `from` lacks start at
// zero; batch-norm statistics are copied.
void Transplant(IgbNetModule& from, IgbNetModule& to);

// Writes the archive to a temporary file beside `path`, then renames it.
void SaveArchiveAtomic(torch::serialize::OutputArchive& archive,
                       const std::string& path);

// The module in eval mode with each batch norm folded into the convolution
// before it (w' = w gamma / sqrt(var + eps), b' = beta - mean gamma /
// sqrt(var + eps)): the same function in a quarter fewer passes over the
// activations, for inference.
// Where libtorch has oneDNN, the convolutions' weights are kept in oneDNN's
// own layout too, so that a batch of two or more images runs the stem and
// the blocks on oneDNN tensors: the same kernels ATen picks for such a
// batch of plain tensors (the same numbers, bit for bit) without a reorder
// of the activations into and out of that layout around every
// convolution. A batch of one keeps ATen's own choice of kernel.
// The stem and the residual blocks as oneDNN runs them: weights reordered
// once into its layout, in one data type.
struct OneDnnLayers {
  torch::Tensor stem_w, stem_b;
  std::vector<std::array<torch::Tensor, 4>> blocks;  // w1, b1, w2, b2
};

struct FoldedNet {
  torch::Tensor stem_w, stem_b;
  std::vector<std::array<torch::Tensor, 4>> blocks;  // w1, b1, w2, b2
  torch::Tensor fc1_w, fc1_b;  // fc1 as a hidden x C x P x P convolution
  torch::Tensor fc1_centre_w;  // its centre's part, hidden x C x c x c
  bool onednn = false;         // f32 below is made
  OneDnnLayers f32;
  bool bf16 = false;  // bf16 below is made (NativeBFloat16Kernels())
  OneDnnLayers bf16_layers;
};
// NativeBFloat16 (network.h) on this side of the plugin.
bool NativeBFloat16Kernels();
FoldedNet Fold(IgbNetModule& module, const NetworkConfig& config);
// Whether FoldedEmbed may take oneDNN's tensors where a FoldedNet has them
// (on until set; the comparison of internal::PlainConvolutions, network.h);
// returns the setting before. Thread-safe.
bool SetOneDnnLayout(bool on);
torch::Tensor FoldedForward(const FoldedNet& f, IgbNetModule& module,
                            const NetworkConfig& config,
                            const torch::Tensor& x);
// The hidden features (IgbNetModuleImpl::embed) through the folded layers.
torch::Tensor FoldedEmbed(const FoldedNet& f, IgbNetModule& module,
                          const NetworkConfig& config, const torch::Tensor& x);

// The network of learning/network.h (IgbNet forwards every call here through
// the plugin's table, torch_backend.h).
class TorchNet {
 public:
  // A freshly initialized network (libtorch's default initialization,
  // seeded).
  TorchNet(const NetworkConfig& config, std::uint64_t seed);
  ~TorchNet();
  TorchNet(const TorchNet&) = delete;
  TorchNet& operator=(const TorchNet&) = delete;
  // As IgbNet::Load.
  static std::unique_ptr<TorchNet> Load(const std::string& path,
                                        const std::string& error_file,
                                        int error_line, const std::string& key);
  void Save(const std::string& path) const;
  const NetworkConfig& config() const;
  const FileIdentity& file() const;
  // Forward (embed false: logits) or Embed (true: hidden features).
  void Infer(const float* images, int batch, int height, int width, bool embed,
             bool bf16, float* out) const;
  void Head(const float* features, const TeamGraph& graph, float* logits) const;
  std::int64_t NumParameters() const;

  struct Impl;
  // The module to change (training): forgets what Infer folded.
  Impl& impl();
  const Impl& impl() const { return *impl_; }

 private:
  TorchNet();
  // The folded layers for inference, built at the first call.
  std::shared_ptr<const FoldedNet> Folded() const;
  std::unique_ptr<Impl> impl_;
};

struct TorchNet::Impl {
  NetworkConfig config;
  FileIdentity file;
  IgbNetModule module{nullptr};
  // Built by the first Infer, dropped by TorchNet::impl() (through which
  // training changes the module).
  std::mutex folded_mutex;
  std::shared_ptr<const FoldedNet> folded;
};

// learning/trainer.h's Train, Validate and MeasureNetworkSpeed (IgbNet's
// side calls them through the plugin's table).
std::vector<EpochLog> TorchTrain(const TrainOptions& options);
ValidationResult TorchValidate(const std::string& model,
                               const std::vector<std::string>& data,
                               double val_share, std::uint64_t seed,
                               bool valid_moves);
double TorchNetworkSpeed(const NetworkConfig& config, int height, int width,
                         int batch, bool train, int iterations, int repeats,
                         bool bf16);

}  // namespace aia

#endif  // AIA_SRC_LEARNING_TORCH_TORCH_NET_H_
