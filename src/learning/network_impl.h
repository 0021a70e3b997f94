// The libtorch side of learning/network.h: private to src/learning (the
// network and the trainer); nothing else includes torch.
#ifndef AIA_SRC_LEARNING_NETWORK_IMPL_H_
#define AIA_SRC_LEARNING_NETWORK_IMPL_H_

#include <torch/torch.h>

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

struct IgbNet::Impl {
  NetworkConfig config;
  FileIdentity file;
  IgbNetModule module{nullptr};
};

}  // namespace aia

#endif  // AIA_SRC_LEARNING_NETWORK_IMPL_H_
