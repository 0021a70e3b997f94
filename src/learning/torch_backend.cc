// Loads the libtorch plugin (src/learning/torch_backend.h) and forwards
// IgbNet, Train, Validate, MeasureNetworkSpeed and the inference threads to
// it.
#include "torch_backend.h"

#include <dlfcn.h>
#include <unistd.h>

#include <atomic>
#include <climits>
#include <stdexcept>
#include <string>
#include <vector>

#include "aia/core/check.h"

#ifndef AIA_TORCH_PLUGIN
#error "AIA_TORCH_PLUGIN: the plugin's path, set by CMakeLists.txt"
#endif

namespace aia {
namespace {

std::atomic<const TorchBackend*> loaded{nullptr};

// Where the plugin may be: where this build wrote it, then beside the
// running program (a build folder moved as a whole).
std::vector<std::string> PluginCandidates() {
  std::vector<std::string> paths = {AIA_TORCH_PLUGIN};
  char exe[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n > 0) {
    std::string dir(exe, static_cast<std::size_t>(n));
    dir.resize(dir.rfind('/') + 1);
    paths.push_back(dir + "libaia_torch.so");
  }
  return paths;
}

const TorchBackend* LoadBackend() {
  std::string tried;
  for (const std::string& path : PluginCandidates()) {
    // RTLD_LOCAL: libtorch's and the plugin's symbols stay out of the
    // process's global scope.
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* why = dlerror();
      tried += "\n  " + path + ": " + (why ? why : "cannot be loaded");
      continue;
    }
    using Entry = const TorchBackend* (*)();
    const auto entry =
        reinterpret_cast<Entry>(dlsym(handle, kTorchBackendSymbol));
    const TorchBackend* table = entry ? entry() : nullptr;
    if (!table || table->version != kTorchBackendVersion ||
        table->size != sizeof(TorchBackend)) {
      tried += "\n  " + path +
               ": not this build's plugin (rebuild: cmake "
               "--build build)";
      continue;
    }
    loaded = table;
    return table;
  }
  throw std::runtime_error(
      "cannot load libtorch's plugin libaia_torch.so (the learned policy and "
      "training need it; build it with `cmake --build build`):" +
      tried);
}

}  // namespace

const TorchBackend& Torch() {
  static const TorchBackend* const table = LoadBackend();
  return *table;
}

const TorchBackend* TorchIfLoaded() { return loaded.load(); }

IgbNet::IgbNet(const TorchBackend* backend, TorchNet* net)
    : backend_(backend), net_(net) {
  AIA_CHECK(backend_ && net_);
}

IgbNet::IgbNet(const NetworkConfig& config, std::uint64_t seed)
    : IgbNet(&Torch(), Torch().create(config, seed)) {}

IgbNet::~IgbNet() { backend_->destroy(net_); }

std::unique_ptr<IgbNet> IgbNet::Load(const std::string& path,
                                     const std::string& error_file,
                                     int error_line, const std::string& key) {
  const TorchBackend& torch = Torch();
  return std::unique_ptr<IgbNet>(
      new IgbNet(&torch, torch.load(path, error_file, error_line, key)));
}

void IgbNet::Save(const std::string& path) const {
  backend_->save(*net_, path);
}

const NetworkConfig& IgbNet::config() const { return backend_->config(*net_); }

const FileIdentity& IgbNet::file() const { return backend_->file(*net_); }

void IgbNet::Forward(const float* images, int batch, int height, int width,
                     float* logits) const {
  backend_->infer(*net_, images, batch, height, width, false, logits);
}

void IgbNet::Embed(const float* images, int batch, int height, int width,
                   float* features) const {
  backend_->infer(*net_, images, batch, height, width, true, features);
}

void IgbNet::Head(const float* features, const TeamGraph& graph,
                  float* logits) const {
  backend_->head(*net_, features, graph, logits);
}

std::int64_t IgbNet::NumParameters() const {
  return backend_->num_parameters(*net_);
}

void SetInferenceThreads(int threads) {
  if (threads > 0) Torch().set_threads(threads);
}

int InferenceThreads() { return Torch().threads(); }

std::vector<EpochLog> Train(const TrainOptions& options) {
  return Torch().train(options);
}

ValidationResult Validate(const std::string& model,
                          const std::vector<std::string>& data,
                          double val_share, std::uint64_t seed) {
  return Torch().validate(model, data, val_share, seed);
}

double MeasureNetworkSpeed(const NetworkConfig& config, int height, int width,
                           int batch, bool train, int iterations, int repeats) {
  return Torch().network_speed(config, height, width, batch, train, iterations,
                               repeats);
}

}  // namespace aia
