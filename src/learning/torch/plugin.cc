// The plugin's table (src/learning/torch_backend.h): each entry calls the
// libtorch implementation of this folder.
#include <torch/torch.h>

#include "../torch_backend.h"
#include "torch_net.h"

namespace {

aia::TorchBackend MakeTable() {
  using aia::TorchNet;
  aia::TorchBackend t;
  t.create = [](const aia::NetworkConfig& config, std::uint64_t seed) {
    return new TorchNet(config, seed);
  };
  t.load = [](const std::string& path, const std::string& error_file,
              int error_line, const std::string& key) {
    return TorchNet::Load(path, error_file, error_line, key).release();
  };
  t.destroy = [](TorchNet* net) { delete net; };
  t.save = [](const TorchNet& net, const std::string& path) { net.Save(path); };
  t.config = [](const TorchNet& net) -> const aia::NetworkConfig& {
    return net.config();
  };
  t.file = [](const TorchNet& net) -> const aia::FileIdentity& {
    return net.file();
  };
  t.infer = [](const TorchNet& net, const float* images, int batch, int height,
               int width, bool embed, bool bfloat16, float* out) {
    net.Infer(images, batch, height, width, embed, bfloat16, out);
  };
  t.head = [](const TorchNet& net, const float* features,
              const aia::TeamGraph& graph,
              float* logits) { net.Head(features, graph, logits); };
  t.num_parameters = [](const TorchNet& net) { return net.NumParameters(); };
  t.train = aia::TorchTrain;
  t.validate = aia::TorchValidate;
  t.network_speed = aia::TorchNetworkSpeed;
  t.set_threads = [](int threads) { torch::set_num_threads(threads); };
  t.threads = [] { return torch::get_num_threads(); };
  t.set_onednn_layout = aia::SetOneDnnLayout;
  t.native_bfloat16 = aia::NativeBFloat16Kernels;
  return t;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) const void*
aia_torch_backend() {
  static const aia::TorchBackend table = MakeTable();
  return &table;
}
