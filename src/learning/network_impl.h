// The libtorch side of learning/network.h: private to src/learning (the
// network and the trainer); nothing else includes torch.
#ifndef AIA_SRC_LEARNING_NETWORK_IMPL_H_
#define AIA_SRC_LEARNING_NETWORK_IMPL_H_

#include <torch/torch.h>

#include <array>
#include <memory>
#include <mutex>
#include <vector>

#include "aia/learning/network.h"

namespace aia {

struct ResidualBlockImpl : torch::nn::Module {
  explicit ResidualBlockImpl(int width);
  torch::Tensor forward(const torch::Tensor& x);
  torch::nn::Conv2d conv1{nullptr}, conv2{nullptr};
  torch::nn::BatchNorm2d bn1{nullptr}, bn2{nullptr};
};
TORCH_MODULE(ResidualBlock);

struct IgbNetModuleImpl : torch::nn::Module {
  explicit IgbNetModuleImpl(const NetworkConfig& config);
  torch::Tensor forward(const torch::Tensor& x);  // N x 4 x H x W -> N x 4
  torch::nn::Conv2d stem{nullptr};
  torch::nn::BatchNorm2d stem_bn{nullptr};
  torch::nn::ModuleList blocks;
  torch::nn::AdaptiveAvgPool2d pool{nullptr};
  torch::nn::Linear fc1{nullptr}, fc2{nullptr};
};
TORCH_MODULE(IgbNetModule);

// Writes the archive to a temporary file beside `path`, then renames it.
void SaveArchiveAtomic(torch::serialize::OutputArchive& archive,
                       const std::string& path);

// The module in eval mode with each batch norm folded into the convolution
// before it (w' = w gamma / sqrt(var + eps), b' = beta - mean gamma /
// sqrt(var + eps)): the same function in a quarter fewer passes over the
// activations, for inference.
struct FoldedNet {
  torch::Tensor stem_w, stem_b;
  std::vector<std::array<torch::Tensor, 4>> blocks;  // w1, b1, w2, b2
};
FoldedNet Fold(IgbNetModule& module);
torch::Tensor FoldedForward(const FoldedNet& f, IgbNetModule& module,
                            const NetworkConfig& config,
                            const torch::Tensor& x);

struct IgbNet::Impl {
  NetworkConfig config;
  FileIdentity file;
  IgbNetModule module{nullptr};
  // Built by the first Forward, dropped by IgbNet::impl() (through which
  // training changes the module).
  std::mutex folded_mutex;
  std::shared_ptr<const FoldedNet> folded;
};

}  // namespace aia

#endif  // AIA_SRC_LEARNING_NETWORK_IMPL_H_
